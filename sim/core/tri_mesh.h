#pragma once
/// A triangle mesh with the per-vertex shading attributes the pipeline carries: what the
/// surfacing writes (boundary and crack meshes) and what the renderer draws.
#include <string>
#include <vector>

#include "sim/core/types.h"

namespace mudcrack {

struct TriMesh {
    std::string name;                    // "boundary" or "crack" (the DCC object name)
    std::vector<Vec3f> positions;        // [m], (n_vertices)
    std::vector<Vec3f> normals;          // unit, (n_vertices) or empty
    std::vector<Vec2f> uvs;              // texture coordinates, (n_vertices) or empty
    std::vector<float> saturation;       // s in [0,1], (n_vertices) or empty
    std::vector<float> alpha;            // NACC hardening state, (n_vertices) or empty
    std::vector<Tri> faces;              // CCW seen from outside, (n_faces)
    std::vector<int32_t> face_fragment;  // fragment id per face, (n_faces) or empty
};

}  // namespace mudcrack
