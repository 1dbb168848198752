// The second (and last) CGAL translation unit besides cgal_mesher.cpp: Polygon_mesh_processing
// checks of the input surface and the AABB-tree UV transfer onto the boundary.
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/measure.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>

#include <sstream>

#include "pipeline/init/boundary_uv.h"
#include "pipeline/init/surface_check.h"
#include "sim/core/error.h"
#include "sim/core/parallel.h"

namespace mudcrack {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using SurfaceMesh = CGAL::Surface_mesh<Point>;
namespace PMP = CGAL::Polygon_mesh_processing;

std::string point_text(const Vec3& p) {
    std::ostringstream s;
    s << "(" << p.x() << ", " << p.y() << ", " << p.z() << ")";
    return s.str();
}

Vec3 to_vec(const Point& p) { return Vec3(p.x(), p.y(), p.z()); }

}  // namespace

Real check_input_surface(const InputSurface& surface, const std::string& name) {
    if (surface.faces.empty()) throw InputError(name + ": no triangles");
    std::vector<std::string> problems = surface_topology_problems(surface, name);
    auto refuse = [&]() {
        std::string text;
        for (const std::string& p : problems) text += (text.empty() ? "" : "\n") + p;
        throw InputError(text);
    };
    if (!problems.empty()) refuse();

    // from here the soup is a closed oriented manifold: CGAL can make it a mesh
    std::vector<Point> points;
    points.reserve(surface.positions.size());
    for (const Vec3& p : surface.positions) points.emplace_back(p.x(), p.y(), p.z());
    std::vector<std::array<size_t, 3>> polygons;
    polygons.reserve(surface.faces.size());
    for (const Tri& t : surface.faces)
        polygons.push_back({size_t(t[0]), size_t(t[1]), size_t(t[2])});
    if (!PMP::is_polygon_soup_a_polygon_mesh(polygons)) {
        problems.push_back(name + ": the faces do not form a manifold polygon mesh");
        refuse();
    }
    SurfaceMesh mesh;
    PMP::polygon_soup_to_polygon_mesh(points, polygons, mesh);

    // self-intersections: pairs of faces that meet other than at a shared edge or vertex
    std::vector<std::pair<SurfaceMesh::Face_index, SurfaceMesh::Face_index>> pairs;
    PMP::self_intersections<CGAL::Parallel_if_available_tag>(faces(mesh), mesh,
                                                             std::back_inserter(pairs));
    if (!pairs.empty()) {
        const auto f = pairs.front().first, g = pairs.front().second;
        Vec3 centroid = Vec3::Zero();
        for (auto v : vertices_around_face(mesh.halfedge(f), mesh))
            centroid += to_vec(mesh.point(v)) / 3;
        problems.push_back(name + ": " + std::to_string(pairs.size()) +
                           " pairs of self-intersecting faces, first between faces " +
                           std::to_string(std::size_t(f)) + " and " +
                           std::to_string(std::size_t(g)) + " near " + point_text(centroid));
    }

    // enclosed volume: positive only when the normals point outward
    const Real volume = PMP::volume(mesh);
    if (!(volume > 0)) {
        std::ostringstream msg;
        msg << name << ": enclosed volume = " << volume
            << " m^3: expected > 0 (faces wound counter-clockwise seen from outside; "
            << (volume < 0 ? "this mesh is inside out: flip its normals)"
                           : "the mesh encloses nothing)");
        problems.push_back(msg.str());
    }
    if (!problems.empty()) refuse();
    return volume;
}

std::vector<CornerUVs> transfer_boundary_uvs(const InputSurface& surface,
                                             const std::vector<Vec3>& X,
                                             const std::vector<Tri>& boundary) {
    if (surface.face_uv.size() != surface.faces.size())
        throw RuntimeError("transfer_boundary_uvs: the input surface has no UVs");
    using Triangle = Kernel::Triangle_3;
    using Primitive = CGAL::AABB_triangle_primitive<Kernel, std::vector<Triangle>::const_iterator>;
    using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;

    std::vector<Triangle> triangles;
    triangles.reserve(surface.faces.size());
    auto point = [&](int32_t v) {
        const Vec3& p = surface.positions[v];
        return Point(p.x(), p.y(), p.z());
    };
    for (const Tri& t : surface.faces)
        triangles.emplace_back(point(t[0]), point(t[1]), point(t[2]));
    Tree tree(triangles.cbegin(), triangles.cend());
    tree.build();
    tree.accelerate_distance_queries();  // built now: lazily it would race between threads

    std::vector<CornerUVs> uv(boundary.size());
    parallel_for(static_cast<int64_t>(boundary.size()), [&](int64_t f) {
        const Tri& t = boundary[f];
        const Vec3 centroid = (X[t[0]] + X[t[1]] + X[t[2]]) / 3;
        for (int c = 0; c < 3; ++c) {
            const Vec3 q = X[t[c]] + 0.01 * (centroid - X[t[c]]);
            const auto hit = tree.closest_point_and_primitive(Point(q.x(), q.y(), q.z()));
            const size_t face = static_cast<size_t>(hit.second - triangles.cbegin());
            // barycentric coordinates of the closest point in the input face
            const Tri& s = surface.faces[face];
            const Vec3 a = surface.positions[s[0]], b = surface.positions[s[1]],
                       d = surface.positions[s[2]];
            const Vec3 p = to_vec(hit.first);
            const Vec3 e1 = b - a, e2 = d - a, r = p - a;
            const Real d11 = e1.dot(e1), d12 = e1.dot(e2), d22 = e2.dot(e2);
            const Real det = d11 * d22 - d12 * d12;
            Real w1 = 0, w2 = 0;
            if (det > 0) {
                w1 = (d22 * r.dot(e1) - d12 * r.dot(e2)) / det;
                w2 = (d11 * r.dot(e2) - d12 * r.dot(e1)) / det;
            }
            const auto& fuv = surface.face_uv[face];
            uv[f][c] = (1 - w1 - w2) * fuv[0] + w1 * fuv[1] + w2 * fuv[2];
        }
    });
    return uv;
}

}  // namespace mudcrack
