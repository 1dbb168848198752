#pragma once
/// The frame-independent part of the particle-core surfacing (docs/physics.md §5.1), built once per
/// tet mesh: unique edges with rest lengths, unique faces, the tet -> edge/face incidence, the
/// edge -> tet incidence that lists a broken edge's interface triangles, and the layout of the
/// boundary skin triangles with their UVs.
///
/// Particle cores are the barycentric dual cells of the tets. Their vertices are rest points
/// (particles, edge midpoints, face centroids, tet centroids), each shared by the 1-4 particles
/// of its simplex; a core-vertex *copy* is a (rest point, owner particle) pair. Copies are
/// implicit here, addressed by (rest point id, owner slot), so nothing of size 12 x n_tets is
/// stored: rest positions are the centroids of the owners' X and are recomputed when needed.
#include <array>
#include <cstdint>
#include <vector>

#include "sim/core/tet_mesh.h"
#include "sim/core/types.h"

namespace mudcrack {

/// Corners (i, j) of a tet's local edge k, and the local edge of a corner pair.
constexpr std::array<std::array<int, 2>, 6> kTetEdgeCorners = {
    {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}}};
constexpr std::array<std::array<int, 4>, 4> kTetLocalEdge = {
    {{-1, 0, 1, 2}, {0, -1, 3, 4}, {1, 3, -1, 5}, {2, 4, 5, -1}}};
/// Outward (CCW seen from outside) corners of the face opposite local corner l of a positively
/// oriented tet.
constexpr std::array<std::array<int, 3>, 4> kTetOutwardFace = {
    {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}}};

/// Kinds of rest points; the owners of a rest point are the corners of its simplex.
enum class RestPointKind : uint8_t {
    Particle = 0,
    EdgeMidpoint = 1,
    FaceCentroid = 2,
    TetCentroid = 3
};

/// A vertex of the boundary skin with its own UV: one rest point (a boundary particle, a
/// boundary-edge midpoint or a boundary-face centroid) split by distinct UVs at texture seams.
struct SkinUvVertex {
    RestPointKind kind;
    int32_t point;      // particle, edge or face id
    int32_t weld_slot;  // first of its owner slots in the boundary weld-slot space
    int32_t out_slot;   // first of its owner slots in the boundary output-vertex slot space
    Vec2 uv;            // interpolated from TetMesh::boundary_uv (or the fallback projection)
};

/// One boundary face as the skin sees it: its tet, its corners in TetMesh::boundary order
/// (outward), and the SkinUvVertex of each of its 7 rest points: corners 0-2, midpoints of
/// corner pairs (0,1), (1,2), (2,0) at 3-5, the centroid at 6.
struct SkinFace {
    int32_t tet;                       // the tet that owns the face
    int8_t opposite;                   // local corner of `tet` not on the face
    std::array<int32_t, 3> corner;     // particle ids, outward order
    std::array<int32_t, 3> edge;       // edge ids of (0,1), (1,2), (2,0)
    int32_t face;                      // unique face id
    std::array<int32_t, 7> uv_vertex;  // SkinUvVertex ids
};

/// Two skin triangles per corner of a boundary face, in SkinFace rest-point indices; the first
/// corner is the owner particle. Both keep the face's outward orientation.
constexpr std::array<std::array<int, 3>, 6> kSkinTriangles = {
    {{0, 3, 6}, {0, 6, 5}, {1, 4, 6}, {1, 6, 3}, {2, 5, 6}, {2, 6, 4}}};

struct CoreTopology {
    int32_t n_particles = 0;
    int32_t n_faces = 0;                            // unique triangle faces of the tets
    std::vector<Vec3> X;                            // rest positions [m], (n_particles)
    std::vector<Tet> tets;                          // positively oriented, (n_tets)
    std::vector<std::array<int32_t, 2>> edges;      // (p < q), sorted, (n_edges)
    std::vector<Real> rest_length;                  // |X_p - X_q| [m], (n_edges)
    std::vector<std::array<int32_t, 6>> tet_edges;  // edge id of local edge k, (n_tets)
    std::vector<std::array<int32_t, 4>> tet_faces;  // face id opposite local corner l, (n_tets)
    std::vector<int32_t> edge_tet_begin;            // CSR offsets into edge_tet, (n_edges + 1)
    std::vector<int32_t> edge_tet;                  // 6 * tet + local edge, grouped by edge
    std::vector<SkinFace> skin_faces;               // (n_boundary faces of TetMesh)
    std::vector<SkinUvVertex> skin_uv_vertices;     // boundary vertices split by UV
    int32_t n_skin_weld_slots = 0;                  // sum of owner counts of boundary rest points
    int32_t n_skin_out_slots = 0;                   // sum of owner counts of skin UV vertices
    Real uv_per_meter = 1;                          // texture density of the boundary UVs [1/m]
    // false: boundary UVs come from the projection
    bool has_boundary_uv = false;

    int32_t n_tets() const { return static_cast<int32_t>(tets.size()); }
    int32_t n_edges() const { return static_cast<int32_t>(edges.size()); }
    /// Bytes held by this structure (for the memory-per-tet figure).
    size_t memory_bytes() const;
};

/// Builds the surfacing topology of a rest tet mesh (docs/physics.md §5.1). Linear time: edges and
/// faces are bucketed by their smallest particle id. Throws InputError (prefixed "tet mesh: ")
/// on an empty mesh, out-of-range ids, a tet with non-positive rest volume, a face shared by more
/// than two tets, or `boundary` not being exactly the outward single-tet faces.
CoreTopology build_core_topology(const TetMesh& mesh);

/// The owners of the face of tet `tet` opposite local corner `l`, sorted by particle id (the
/// order of the face weld tables), and the ids of the edges between them: edge[k] joins the
/// owners kFaceEdgeOwners[k] (weld_classes.h).
struct FaceOwners {
    std::array<int32_t, 3> owner;
    std::array<int32_t, 3> edge;
};
FaceOwners face_owners(const CoreTopology& topo, int32_t tet, int l);

/// The planar UV projection used where no UVs exist (crack faces, boundaries without UVs):
/// rest position projected along the dominant axis of the rest normal n0 (x: (z, y),
/// y: (x, z), z: (x, y)), times uv_per_meter. Textures therefore stay put on the soil.
Vec2 triplanar_uv(const Vec3& rest_position, int axis, Real uv_per_meter);
/// The dominant axis (0, 1, 2) of a normal.
int dominant_axis(const Vec3& n);

}  // namespace mudcrack
