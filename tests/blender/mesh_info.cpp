// blender_test_mesh_info FILE...: what the Blender playback test expects of each mesh file, read
// with the pipeline's own reader (pipeline/io/mesh_io.h: assimp), independently of the add-on's
// pure-Python reader. One JSON object on stdout, keyed by the file as given:
//   {"FILE": {"vertices": n, "faces": m, "normals": bool, "uvs": bool, "colors": bool,
//             "position_sum": [x, y, z], "uv0": [u, v], "color0": [r, g]}, ...}
// (position_sum over every vertex; uv0 and color0 of vertex 0, color0 = (saturation,
// logistic(alpha)) as written). Exit 1 naming the file when one cannot be read.
#include <cmath>
#include <cstdio>
#include <exception>

#include "pipeline/io/mesh_io.h"

int main(int argc, char** argv) {
    using namespace mudcrack;
    if (argc < 2) {
        std::fprintf(stderr, "usage: blender_test_mesh_info FILE...\n");
        return 2;
    }
    std::printf("{");
    for (int i = 1; i < argc; ++i) {
        std::vector<TriMesh> meshes;
        try {
            meshes = import_meshes(argv[i]);
        } catch (const std::exception& e) {
            std::fprintf(stderr, "blender_test_mesh_info: %s\n", e.what());
            return 1;
        }
        size_t vertices = 0, faces = 0;
        bool normals = !meshes.empty(), uvs = !meshes.empty(), colors = !meshes.empty();
        double sum[3] = {0, 0, 0};
        for (const TriMesh& m : meshes) {
            vertices += m.positions.size();
            faces += m.faces.size();
            normals = normals && m.normals.size() == m.positions.size();
            uvs = uvs && m.uvs.size() == m.positions.size();
            colors = colors && m.saturation.size() == m.positions.size() && m.alpha.size() == m.positions.size();
            for (const Vec3f& p : m.positions)
                for (int k = 0; k < 3; ++k) sum[k] += p[k];
        }
        std::printf("%s\n\"%s\": {\"vertices\": %zu, \"faces\": %zu, \"normals\": %s, \"uvs\": %s, \"colors\": %s, "
                    "\"position_sum\": [%.9g, %.9g, %.9g]",
                    i > 1 ? "," : "", argv[i], vertices, faces, normals ? "true" : "false", uvs ? "true" : "false",
                    colors ? "true" : "false", sum[0], sum[1], sum[2]);
        if (!meshes.empty() && !meshes[0].positions.empty()) {
            const TriMesh& m = meshes[0];
            if (uvs) std::printf(", \"uv0\": [%.9g, %.9g]", m.uvs[0].x(), m.uvs[0].y());
            if (colors)
                std::printf(", \"color0\": [%.9g, %.9g]", m.saturation[0], 1.0 / (1.0 + std::exp(-double(m.alpha[0]))));
        }
        std::printf("}");
    }
    std::printf("\n}\n");
    return 0;
}
