// All of CGAL Mesh_3 lives in this one translation unit (~80 s and ~3 GB to compile): keep it
// small and keep CGAL out of headers.
#include "pipeline/init/cgal_mesher.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Mesh_complex_3_in_triangulation_3.h>
#include <CGAL/Mesh_criteria_3.h>
#include <CGAL/Mesh_triangulation_3.h>
#include <CGAL/Polyhedral_mesh_domain_with_features_3.h>
#include <CGAL/Random.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/make_mesh_3.h>
// after make_mesh_3.h, which brings the worksharing types the parallel optimisers need
#include <CGAL/exude_mesh_3.h>
#include <CGAL/perturb_mesh_3.h>

#include <tbb/global_control.h>

#include <algorithm>
#include <exception>
#include <sstream>
#include <unordered_map>
#include <utility>

#include "sim/core/check.h"
#include "sim/core/error.h"
#include "sim/core/log.h"
#include "sim/core/parallel.h"

namespace mudcrack {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using SurfaceMesh = CGAL::Surface_mesh<Kernel::Point_3>;
using Domain = CGAL::Polyhedral_mesh_domain_with_features_3<Kernel, SurfaceMesh>;

SurfaceMesh to_surface_mesh(const InputSurface& surface) {
    SurfaceMesh sm;
    sm.reserve(static_cast<SurfaceMesh::size_type>(surface.positions.size()),
               static_cast<SurfaceMesh::size_type>(3 * surface.faces.size() / 2),
               static_cast<SurfaceMesh::size_type>(surface.faces.size()));
    std::vector<SurfaceMesh::Vertex_index> v;
    v.reserve(surface.positions.size());
    for (const Vec3& p : surface.positions)
        v.push_back(sm.add_vertex(Kernel::Point_3(p.x(), p.y(), p.z())));
    for (size_t f = 0; f < surface.faces.size(); ++f) {
        const Tri& t = surface.faces[f];
        if (sm.add_face(v[t[0]], v[t[1]], v[t[2]]) == SurfaceMesh::null_face()) {
            std::ostringstream msg;
            msg << "CGAL Mesh_3: face " << f << " (" << t[0] << ", " << t[1] << ", " << t[2]
                << ") breaks manifoldness; run check_input_surface before meshing";
            throw RuntimeError(msg.str());
        }
    }
    return sm;
}

/// Runs make_mesh_3 with the given concurrency tag and converts the complex's cells.
template <class ConcurrencyTag>
TetMesh run_mesh_3(Domain& domain, const MesherOptions& o) {
    using Tr = typename CGAL::Mesh_triangulation_3<Domain, CGAL::Default, ConcurrencyTag>::type;
    using C3t3 = CGAL::Mesh_complex_3_in_triangulation_3<Tr, typename Domain::Corner_index,
                                                         typename Domain::Curve_index>;
    using Criteria = CGAL::Mesh_criteria_3<Tr>;
    namespace p = CGAL::parameters;

    const Real L = o.edge_length;
    const Criteria criteria(p::edge_size = L,  // protecting balls along sharp features
                            p::facet_angle = o.facet_angle, p::facet_size = o.facet_size_ratio * L,
                            p::facet_distance = o.facet_distance_ratio * L,
                            p::cell_radius_edge_ratio = o.cell_radius_edge_ratio,
                            p::cell_size = o.cell_size_ratio * L);
    // refinement only; lloyd and odt stay off, perturb and exude run on request (their
    // runtime switch lives here rather than in make_mesh_3's typed parameters)
    C3t3 c3t3 = CGAL::make_mesh_3<C3t3>(domain, criteria, p::no_perturb(), p::no_exude());
    if (o.perturb) CGAL::perturb_mesh_3(c3t3, domain, p::time_limit = o.optimizer_time_limit);
    if (o.exude) CGAL::exude_mesh_3(c3t3, p::time_limit = o.optimizer_time_limit);

    // number the vertices the complex's cells use, in first-use order (drops far points)
    const auto point_of = c3t3.triangulation().geom_traits().construct_point_3_object();
    std::unordered_map<const void*, int32_t> id_of;
    TetMesh mesh;
    mesh.tets.reserve(static_cast<size_t>(c3t3.number_of_cells_in_complex()));
    for (auto c = c3t3.cells_in_complex_begin(); c != c3t3.cells_in_complex_end(); ++c) {
        Tet tet;
        for (int k = 0; k < 4; ++k) {
            const auto vh = c->vertex(k);
            const auto [it, is_new] = id_of.emplace(&*vh, static_cast<int32_t>(mesh.X.size()));
            if (is_new) {
                const auto q = point_of(vh->point());
                mesh.X.emplace_back(q.x(), q.y(), q.z());
            }
            tet[k] = it->second;
        }
        // Triangulation_3 cells are positively oriented; keep ours so even if a sliver rounds
        if (signed_tet_volume(mesh.X[tet[0]], mesh.X[tet[1]], mesh.X[tet[2]], mesh.X[tet[3]]) < 0)
            std::swap(tet[2], tet[3]);
        mesh.tets.push_back(tet);
    }
    return mesh;
}

}  // namespace

TetMesh tetrahedralize_surface(const InputSurface& surface, const MesherOptions& options) {
    MC_CHECK_GT(options.edge_length, 0);  // mesher_options derives 0 from /sim/h > 0
    // Mesh_3 draws from two generators: the default one, and the domain's own for its initial
    // points, which is CGAL::Random(0) unless the domain is given one (so reseeding the default
    // alone left every seed with the same mesh: a bunny's particles were the same bytes for seeds
    // 1 and 2). Seed both; the domain's with seed - 1, so the default seed 1 keeps the meshes
    // CGAL's Random(0) gave before the seed reached the domain.
    CGAL::get_default_random() = CGAL::Random(options.seed);
    CGAL::Random domain_random(options.seed - 1u);
    TetMesh mesh;
    try {
        const SurfaceMesh sm = to_surface_mesh(surface);
        Domain domain(sm);
        domain.set_random_generator(&domain_random);
        if (options.feature_angle > 0) domain.detect_features(options.feature_angle);
        if (options.parallel) {
            // honour --threads for TBB as parallel_for does for OpenMP
            tbb::global_control threads(tbb::global_control::max_allowed_parallelism,
                                        static_cast<size_t>(std::max(1, thread_count())));
            mesh = run_mesh_3<CGAL::Parallel_tag>(domain, options);
        } else {
            mesh = run_mesh_3<CGAL::Sequential_tag>(domain, options);
        }
    } catch (const RuntimeError&) {
        throw;
    } catch (const std::exception& e) {
        throw RuntimeError(std::string("CGAL Mesh_3 failed: ") + e.what());
    }
    if (mesh.tets.empty()) {
        throw RuntimeError(
            "CGAL Mesh_3 produced no tets at edge_length = " + std::to_string(options.edge_length) +
            " m: the edge length is probably too large for the object");
    }
    return mesh;
}

}  // namespace mudcrack
