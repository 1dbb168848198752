#pragma once
/// Smooth crack walls for the plates surfacing (docs/physics.md §5.7). The crack faces of the
/// particle-core method are the barycentric dual of the cut edges: each wall vertex sits at a
/// cut edge's midpoint, a face centroid or a tet centroid, so a wall that crosses the lattice
/// at an angle is a staircase at the cell's scale, and its rim on the top a saw-tooth.
///
/// Here the wall is placed as a smoothed cut instead (the mass points of dual contouring): it
/// crosses each cut edge where a smoothed side field changes sign, at a point that then slides
/// along that edge (5-95 % of the way) under Taubin smoothing of the crossings in the rest
/// configuration, and a face's or a tet's wall vertex is
/// the mean of its cut edges' crossings. A cut along a lattice plane becomes that plane. Every
/// wall vertex stays inside its own simplex, so each wall still lies between the particles it
/// separates and every skin triangle keeps its orientation; crossings on the boundary follow
/// only their rim neighbours, so the rim becomes a smooth curve and stays a sharp edge. Both
/// sides of a wall and the skin read the same rest points, so walls still meet where a crack
/// is closed.
#include <array>
#include <cstdint>
#include <vector>

#include "sim/core/types.h"
#include "surfacing/core_topology.h"
#include "surfacing/weld_classes.h"

namespace mudcrack {

/// The rest positions that smoothing moved, by rest point; every other rest point keeps its own.
/// Dense slot tables (one int per edge, face and tet) point into the moved positions, so a lookup
/// is two loads: the skin and the walls look up every rest point they use.
class WallRestPositions {
public:
    WallRestPositions() = default;
    WallRestPositions(int32_t n_edges, int32_t n_faces, int32_t n_tets)
        : m_slot{std::vector<int32_t>(n_edges, -1), std::vector<int32_t>(n_faces, -1),
                 std::vector<int32_t>(n_tets, -1)} {}
    /// The rest position of (kind, id): the smoothed one when it is on a wall, else y0.
    Vec3 of(RestPointKind kind, int32_t id, const Vec3& y0) const {
        if (m_moved.empty() || kind == RestPointKind::Particle) return y0;
        const int32_t slot = m_slot[int(kind) - 1][id];
        return slot < 0 ? y0 : m_moved[slot];
    }
    size_t size() const { return m_moved.size(); }
    /// Frees the slack push_back left in the moved positions, once they are all set.
    void shrink_to_fit() { m_moved.shrink_to_fit(); }
    void set(RestPointKind kind, int32_t id, const Vec3& y) {
        int32_t& slot = m_slot[int(kind) - 1][id];
        if (slot < 0) {
            slot = static_cast<int32_t>(m_moved.size());
            m_moved.push_back(y);
        } else {
            m_moved[slot] = y;
        }
    }

private:
    std::array<std::vector<int32_t>, 3> m_slot;  // edge, face, tet -> index into m_moved, or -1
    std::vector<Vec3> m_moved;
};

/// The walls through a shot's last cut edges as a graph, for smoothing them where they are. A wall
/// smooth in the rest state still crumples where its particles moved unevenly; smoothing the
/// frame's own wall mesh takes that out, but its vertices and their neighbours change as cracks
/// grow, so the smoothing of a vertex changed with them and it popped. The graph is fixed for the
/// shot: a node per weld class of each wall rest point under the last frame's cuts (a side of a
/// wall), joined as the last frame's wall triangles join them. Each frame smooths the same graph
/// (smooth_wall_nodes), and a vertex of that frame's walls, whose class holds one or more of
/// these nodes, is made from their smoothed positions: a linear, fixed filter of the particles,
/// as continuous in time as they are.
struct WallGraph {
    struct Point {
        RestPointKind kind = RestPointKind::EdgeMidpoint;
        int32_t id = 0;   // edge, face or tet id
        int32_t tet = 0;  // a face: a tet holding it, and its corner opposite it
        int8_t corner = 0;
        WeldReps reps{};         // its owners' classes under the last frame's cuts
        int32_t first_node = 0;  // node of owner slot j's class: first_node + reps[j]
    };
    std::vector<Point> points;                     // the rest points of the walls
    std::array<std::vector<int32_t>, 3> point_of;  // edge, face, tet id -> index into points, or -1
    std::vector<int32_t> begin, neighbour;         // CSR of each node's neighbours, (n_nodes + 1)
    std::vector<uint8_t> held;                     // a node on the boundary (the rim) or hidden:
                                                   // not smoothed over the wall
    std::vector<uint8_t> hidden;                   // a node of a wall that reaches no surface
    // the nodes smoothing moves: not held, with neighbours
    std::vector<int32_t> free_nodes;
    /// The rim nodes smoothed along the rim: each has exactly two neighbours on the rim, so the rim
    /// is a curve through it (its ends, and where three cracks meet on the surface, stay put).
    /// Both the wall and the skin use a rim node, so the skin follows it.
    std::vector<int32_t> rim_nodes;
    std::vector<std::array<int32_t, 2>> rim_neighbours;  // (rim_nodes)
    int32_t n_nodes = 0;

    bool empty() const { return points.empty(); }
    /// Index into points of rest point (kind, id), or -1 when it is on no wall.
    int32_t find(RestPointKind kind, int32_t id) const {
        if (points.empty() || kind == RestPointKind::Particle) return -1;
        return point_of[int(kind) - 1][id];
    }
};

/// The graph of the walls through the edges with is_cut[e] != 0. Deterministic.
WallGraph plan_wall_graph(const CoreTopology& topo, const std::vector<uint8_t>& is_cut);

/// `steps` Taubin steps (lambda 0.67, mu -0.72) of the node positions over the graph, and of the
/// rim nodes along the rim; held nodes and nodes without neighbours kept. Then each node keeps
/// 5 % of where it started, so the two sides of a crack never become one. Deterministic whatever
/// the thread count.
void smooth_wall_nodes(const WallGraph& graph, int steps, std::vector<Vec3>& position);

/// Places the walls through the edges with is_cut[e] != 0, with `iterations` Taubin steps
/// (lambda 0.67, mu -0.72: a low-pass filter that does not shrink the wall) on the crossings.
/// 0 iterations moves nothing (the dual-cell walls of the other modes). Deterministic.
WallRestPositions smooth_walls(const CoreTopology& topo, const std::vector<uint8_t>& is_cut,
                               int iterations);

}  // namespace mudcrack
