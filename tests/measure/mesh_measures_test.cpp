// mc-measure's mesh measures (pipeline/measure/mesh_measures.h) on a slab torn in two, surfaced in
// the plates mode: pieces and closed pieces, and the frame-to-frame vertex jumps that a crack
// opening with its particles does not count and a wall that snaps does.
#include <gtest/gtest.h>

#include <cmath>

#include "pipeline/measure/mesh_measures.h"
#include "surfacing/core_surface.h"
#include "surfacing/edge_breaks.h"
#include "surfacing/lattice_mesh.h"
#include "tolerance.h"

namespace mudcrack {
namespace {

constexpr double kH = 0.1;  // lattice spacing [m]

int column_of(const Vec3& X) { return int(std::lround(X.x() / kH)); }

/// A 12 x 3 x 4 slab whose edges that touch columns 5 and 6 break at `break_frame`.
struct Slab {
    TetMesh mesh = test::box_lattice(12, 3, 4, kH);
    CoreTopology topo = build_core_topology(mesh);
    std::vector<int32_t> first_break = no_edge_breaks(topo);

    explicit Slab(int break_frame) {
        for (int32_t e = 0; e < topo.n_edges(); ++e) {
            const int a = column_of(topo.X[topo.edges[e][0]]),
                      b = column_of(topo.X[topo.edges[e][1]]);
            if (a == 5 || a == 6 || b == 5 || b == 6) first_break[e] = break_frame;
        }
    }
    /// Frame n: everything moved by `shift`, the right part (columns 6-12) by dx more.
    ParticleFrame frame(int n, double dx, const Vec3& shift = Vec3::Zero()) const {
        ParticleFrame f;
        f.frame = n;
        for (const Vec3& X : topo.X) {
            f.P.push_back((X + shift + Vec3(column_of(X) >= 6 ? dx : 0, 0, 0)).cast<float>());
            f.Fe.push_back(Mat3f::Identity());
        }
        return f;
    }
};

SurfaceParams plates() {
    SurfaceParams p;
    p.mode = SurfaceMode::Plates;
    p.cell_size = 2 * kH;
    p.min_piece_size = 1;
    p.close_gaps = 0;
    return p;
}

TEST(MeshMeasures, ASlabTornInTwoIsTwoClosedPiecesAndNoChips) {
    const Slab slab(1);
    const SurfacedFrame s =
        surface_frame(slab.topo, slab.frame(1, 0.05), slab.first_break, plates());
    const MeshPieces m = measure_mesh_pieces(s.boundary, s.crack, 2 * kH);
    EXPECT_EQ(m.pieces, 2);
    EXPECT_EQ(m.chips, 0);
    EXPECT_EQ(m.open_pieces, 0);
    EXPECT_EQ(m.open_edges, 0);
    EXPECT_EQ(m.hole_edges, 0);
    // one wall across the slab's 0.3 x 0.4 m section, a side
    EXPECT_NEAR(m.crack_area, 0.3 * 0.4, 0.1 * 0.3 * 0.4);
    EXPECT_LT(m.crack_roughness_deg, 10);
}

TEST(MeshMeasures, AMissingTriangleIsAHoleAndTheTwoSidesOfAClosedCrackAreNot) {
    // two closed tetrahedra that touch along an edge, as the two sides of a crack not yet open
    // do: that edge has four triangles
    TriMesh two;
    for (const float s : {1.0f, -1.0f})  // the second: the first turned half a turn about x
        for (const Vec3f& x : {Vec3f(0, 0, 0), Vec3f(1, 0, 0), Vec3f(0, s, 0), Vec3f(0, 0, s)})
            two.positions.push_back(x);
    for (const int32_t o : {0, 4})
        for (const Tri& t : {Tri{0, 2, 1}, Tri{0, 1, 3}, Tri{0, 3, 2}, Tri{1, 2, 3}})
            two.faces.push_back(Tri{o + t[0], o + t[1], o + t[2]});
    const MeshPieces touching = measure_mesh_pieces(two, TriMesh{}, 2 * kH);
    EXPECT_EQ(touching.open_edges, 1);
    EXPECT_EQ(touching.hole_edges, 0);
    // a wall triangle taken out of the open crack: its three edges are a hole's rim
    const Slab slab(1);
    SurfacedFrame holed = surface_frame(slab.topo, slab.frame(1, 0.05), slab.first_break, plates());
    ASSERT_FALSE(holed.crack.faces.empty());
    holed.crack.faces.pop_back();
    holed.crack.face_fragment.pop_back();
    const MeshPieces m = measure_mesh_pieces(holed.boundary, holed.crack, 2 * kH);
    EXPECT_EQ(m.hole_edges, 3);
    EXPECT_EQ(m.open_edges, 3);
    EXPECT_EQ(m.open_pieces, 1);
}

TEST(MeshMeasures, VerticesThatMoveWithTheirParticlesDoNotJumpEvenAsTheCrackOpens) {
    const Slab slab(1);
    const SurfaceParams params = plates();
    const ParticleFrame a = slab.frame(1, 0.05), b = slab.frame(2, 0.15, Vec3(0.3, -0.2, 0.1));
    const SurfacedFrame sa = surface_frame(slab.topo, a, slab.first_break, params);
    const SurfacedFrame sb = surface_frame(slab.topo, b, slab.first_break, params);
    const SurfaceMotion m = measure_surface_motion(slab.topo, sa, a, sb, b, 2 * kH);
    EXPECT_GT(m.vertices_compared, 0);
    EXPECT_NEAR(m.jump_max_cells, 0, tol::kFloat);
    EXPECT_EQ(m.piece_changes, 0);
}

TEST(MeshMeasures, AWallThatSnapsOpenInOneFrameJumps) {
    // the band 0.2 m open and welded at frame 1; cut at frame 2, surfaced on its own, each side's
    // wall vertices leave the middle of the band for their own side: 0.1 m = half a cell
    const Slab slab(2);
    const SurfaceParams params = plates();
    const ParticleFrame a = slab.frame(1, 0.2), b = slab.frame(2, 0.2);
    const SurfacedFrame sa = surface_frame(slab.topo, a, slab.first_break, params);
    const SurfacedFrame sb = surface_frame(slab.topo, b, slab.first_break, params);
    const SurfaceMotion m = measure_surface_motion(slab.topo, sa, a, sb, b, 2 * kH);
    EXPECT_GT(m.jump_max_cells, 0.4);
}

}  // namespace
}  // namespace mudcrack
