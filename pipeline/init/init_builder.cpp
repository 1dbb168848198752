#include "pipeline/init/init_builder.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "pipeline/init/boundary_uv.h"
#include "pipeline/init/heightfield.h"
#include "pipeline/init/lattice.h"
#include "pipeline/init/surface_check.h"
#include "sim/core/check.h"
#include "sim/core/error.h"
#include "sim/core/log.h"
#include "sim/core/stats.h"

namespace mudcrack {
namespace {

std::string num(Real v) {
    std::ostringstream s;
    s << v;
    return s.str();
}

// The closed surface of the box [lo, hi]: 8 corners (corner i at hi on axis d when bit d of i is
// set), two triangles per face, counter-clockwise seen from outside.
InputSurface box_surface(const Vec3& lo, const Vec3& hi) {
    InputSurface s;
    for (int i = 0; i < 8; ++i)
        s.positions.emplace_back(i & 1 ? hi.x() : lo.x(), i & 2 ? hi.y() : lo.y(),
                                 i & 4 ? hi.z() : lo.z());
    for (int d = 0; d < 3; ++d) {
        // (e, f, d) is right-handed, so corners (0,0), (1,0), (1,1), (0,1) in (e, f) turn
        // counter-clockwise about +d
        const int e = (d + 1) % 3, f = (d + 2) % 3;
        for (int side = 0; side < 2; ++side) {
            const int base = side << d;
            int quad[4] = {base, base | (1 << e), base | (1 << e) | (1 << f), base | (1 << f)};
            if (side == 0) std::swap(quad[1], quad[3]);  // facing -d
            s.faces.push_back({quad[0], quad[1], quad[2]});
            s.faces.push_back({quad[0], quad[2], quad[3]});
        }
    }
    return s;
}

// The closed surface of the elliptic cylinder inscribed in the box [lo, hi] (a round puddle on a
// square box): its rims are polygons of vertices on the ellipse, each side a chord of at most
// half the mesher's edge length `edge` (Mesh_3 protects the rims, whose faces meet at 90
// degrees, and meshes the sides, which turn by under a degree from chord to chord), its top and
// bottom fans about their centres; counter-clockwise seen from outside
InputSurface elliptic_cylinder_surface(const Vec3& lo, const Vec3& hi, Real edge) {
    const Real a = (hi.x() - lo.x()) / 2, b = (hi.z() - lo.z()) / 2;
    const Real cx = (lo.x() + hi.x()) / 2, cz = (lo.z() + hi.z()) / 2;
    // Ramanujan's perimeter of the ellipse
    const Real perimeter = kPi * (3 * (a + b) - std::sqrt((3 * a + b) * (a + 3 * b)));
    const int n = std::max(32, static_cast<int>(std::ceil(perimeter / (edge / 2))));
    InputSurface s;
    for (int ring = 0; ring < 2; ++ring)  // bottom ring 0..n-1, top ring n..2n-1
        for (int i = 0; i < n; ++i) {
            const Real t = 2 * kPi * i / n;
            s.positions.emplace_back(cx + a * std::cos(t), ring ? hi.y() : lo.y(),
                                     cz + b * std::sin(t));
        }
    const int bottom = 2 * n, top = 2 * n + 1;
    s.positions.emplace_back(cx, lo.y(), cz);
    s.positions.emplace_back(cx, hi.y(), cz);
    // t runs from x toward z, so the top's fan faces +y turning against t and the bottom's
    // faces -y turning with it; a side quad is (bottom i, top i, top i + 1) and (bottom i,
    // top i + 1, bottom i + 1), facing out
    for (int i = 0; i < n; ++i) {
        const int j = (i + 1) % n;
        s.faces.push_back({bottom, i, j});
        s.faces.push_back({top, n + j, n + i});
        s.faces.push_back({i, n + i, n + j});
        s.faces.push_back({i, n + j, j});
    }
    return s;
}

// A closed surface, checked and tetrahedralized by Mesh_3 (`check_bounds`, when given, sees its
// bounds first); `name` is how the messages call it (a file, or the box's keys)
InitResult tetrahedralize_checked(const InputSurface& surface, const std::string& name,
                                  const MesherOptions& mesher,
                                  const SurfaceBoundsCheck& check_bounds) {
    const Real surface_volume = check_input_surface(surface, name);
    Vec3 lo = surface.positions[0], hi = lo;
    for (const Vec3& x : surface.positions) lo = lo.cwiseMin(x), hi = hi.cwiseMax(x);
    // before the edge length's checks: a /sim/h too large for the body is h's fault, not
    // the edge length's it derives
    if (check_bounds) check_bounds(lo, hi);
    if (mesher.edge_length > (hi - lo).maxCoeff())
        throw ShotValueError("/init/edge_length = " + num(mesher.edge_length) + " m: larger than " +
                             name + " itself (largest extent " + num((hi - lo).maxCoeff()) +
                             " m after scaling); expected a fraction of it");
    // a quality Mesh_3 mesh has about one vertex per 0.55 L^3 (see default_edge_length)
    const double expected = surface_volume / (0.55 * std::pow(mesher.edge_length, 3));
    if (expected > kMaxInitParticles)
        throw ShotValueError("/init/edge_length = " + num(mesher.edge_length) + " m: would make ~" +
                             count_text(expected) + " particles from " + name + " (volume " +
                             num(surface_volume) + " m^3); expected at most " +
                             count_text(kMaxInitParticles) +
                             ": raise the edge length (or /sim/h when it is derived)");
    log::info("input surface " + name + ": " + std::to_string(surface.positions.size()) +
              " vertices, " + std::to_string(surface.faces.size()) + " triangles, volume " +
              num(surface_volume) + " m^3");
    WallTimer mesh_timer;
    TetMesh tets = tetrahedralize_surface(surface, mesher);
    log::info("CGAL Mesh_3 (" + std::string(mesher.parallel ? "parallel" : "sequential") +
              ", edge length " + num(mesher.edge_length) + " m): " +
              std::to_string(tets.tets.size()) + " tets in " + num(mesh_timer.seconds()) + " s");
    InitResult r = finish_tet_mesh(std::move(tets), &surface);
    r.surface_volume = surface_volume;
    r.edge_length = mesher.edge_length;
    return r;
}

}  // namespace

Real default_edge_length(Real h) { return Real(0.6) * h; }

MesherOptions mesher_options(const InitParams& params, Real h) {
    MC_CHECK_GT(h, 0);  // the shot spec refuses /sim/h <= 0
    MesherOptions o;
    o.edge_length = params.edge_length > 0 ? params.edge_length : default_edge_length(h);
    o.seed = params.seed;
    return o;
}

InputSurface load_placed_surface(const MeshSource& source) {
    InputSurface surface = load_input_surface(source.path);
    for (Vec3& p : surface.positions) p = source.scale * p + source.translate;
    if (source.fit_to_ground && !surface.positions.empty()) {
        Real lowest = surface.positions[0].y();
        for (const Vec3& p : surface.positions) lowest = std::min(lowest, p.y());
        for (Vec3& p : surface.positions) p.y() -= lowest;
    }
    return surface;
}

InitResult finish_tet_mesh(TetMesh mesh, const InputSurface* uv_source) {
    drop_unused_vertices(mesh);
    if (const int64_t bad = count_non_positive_tets(mesh); bad > 0)
        throw RuntimeError("init mesh: " + std::to_string(bad) + " of " +
                           std::to_string(mesh.tets.size()) + " tets have non-positive volume");
    mesh.boundary = extract_boundary_faces(mesh.tets);
    InitResult r;
    if (uv_source && !uv_source->face_uv.empty()) {
        mesh.boundary_uv = transfer_boundary_uvs(*uv_source, mesh.X, mesh.boundary);
        r.uv_method = "transferred";
    } else {
        mesh.boundary_uv = project_boundary_uvs(mesh.X, mesh.boundary);
        r.uv_method = "box projection";
    }
    r.volume0 = particle_rest_volumes(mesh);
    r.quality = measure_quality(mesh);
    r.mesh = std::move(mesh);
    return r;
}

InitResult build_init(const InitParams& params, const MesherOptions& mesher,
                      const SurfaceBoundsCheck& check_bounds) {
    WallTimer timer;
    InitResult r;
    switch (params.type) {
        case SourceType::Box:
            // the loader has checked the box against the shot (as check_bounds does a mesh's)
            if (params.box.lattice == Lattice::Mesh && params.box.footprint == Footprint::Ellipse)
                r = tetrahedralize_checked(
                    elliptic_cylinder_surface(params.box.min, params.box.max, mesher.edge_length),
                    "the box's ellipse (/source/box)", mesher, {});
            else if (params.box.lattice == Lattice::Mesh)
                r = tetrahedralize_checked(box_surface(params.box.min, params.box.max),
                                           "the box (/source/box)", mesher, {});
            else
                r = finish_tet_mesh(make_box_tets(params.box, params.seed), nullptr);
            break;
        case SourceType::Heightfield:
            if (params.heightfield.lattice == HeightfieldLattice::Mesh)
                r = tetrahedralize_checked(heightfield_surface(params.heightfield),
                                           "the heightfield (/source/heightfield)", mesher, {});
            else
                r = finish_tet_mesh(make_heightfield_tets(params.heightfield), nullptr);
            break;
        case SourceType::Mesh:
            if (params.mesh.path.empty())
                throw ShotValueError(
                    "/source/mesh/path: missing: a mesh source needs a surface file");
            r = tetrahedralize_checked(load_placed_surface(params.mesh), params.mesh.path, mesher,
                                       check_bounds);
            break;
    }
    // the heterogeneous strength, a function of the rest positions and the seed
    if (params.strength_field)
        r.strength = strength_multipliers(make_strength_field(*params.strength_field, params.seed),
                                          r.mesh.X);
    const MeshQuality& q = r.quality;
    std::ostringstream msg;
    msg << source_type_name(params.type) << ": " << q.particles << " particles, " << q.tets
        << " tets, " << q.boundary_faces << " boundary faces (UVs: " << r.uv_method
        << "), dihedral angles " << q.min_dihedral_deg << " to " << q.max_dihedral_deg
        << " deg, mean edge " << q.mean_edge_length << " m, volume " << q.tet_volume << " m^3";
    if (r.surface_volume > 0)
        msg << " (" << 100 * (q.tet_volume / r.surface_volume - 1) << " % vs the input surface)";
    msg << ", built in " << timer.seconds() << " s";
    log::info(msg.str());
    return r;
}

InitResult build_init(const InitParams& params, Real h) {
    return build_init(params, mesher_options(params, h));
}

}  // namespace mudcrack
