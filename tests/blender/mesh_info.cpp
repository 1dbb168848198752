// blender_test_mesh_info FILE...: what the Blender playback test expects of each mesh file, read
// with the pipeline's own reader (pipeline/io/mesh_io.h: assimp), independently of the add-on's
// pure-Python reader. One JSON object on stdout, keyed by the file as given:
//   {"FILE": {"vertices": n, "faces": m, "normals": bool, "uvs": bool, "colors": bool,
//             "position_sum": [x, y, z], "uv0": [u, v], "color0": [r, g],
//             "pieces": k, "piece_id_sum": s, "piece_face_sum": t}, ...}
// (position_sum over every vertex; uv0 and color0 of vertex 0, color0 = (saturation,
// logistic(alpha)) as written; the piece keys when the file has fragment ids (UV channel 1):
// the number of distinct ids, their sum, and the sum of every face's id, which a face given
// another piece changes). Debris files (debris.####.ply), read with pipeline/io/debris_io.h:
//   {"FILE": {"points": n, "position_sum": [x, y, z], "velocity_sum": [x, y, z],
//             "pscale_sum": r, "id_sum": i, "piece_sum": p}}
// Exit 1 naming the file when one cannot be read.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <set>
#include <string>

#include "pipeline/io/debris_io.h"
#include "pipeline/io/mesh_io.h"

using namespace mudcrack;

namespace {

bool is_debris_file(const char* path) {
    return std::filesystem::path(path).filename().string().rfind("debris.", 0) == 0;
}

void print_debris_info(const char* path) {
    const DebrisPoints d = read_debris_ply(path);
    double position[3] = {0, 0, 0}, velocity[3] = {0, 0, 0}, pscale = 0;
    int64_t ids = 0, pieces = 0;
    for (size_t i = 0; i < d.size(); ++i) {
        for (int k = 0; k < 3; ++k) {
            position[k] += d.position[i][k];
            velocity[k] += d.velocity[i][k];
        }
        pscale += d.radius[i];
        ids += d.id[i];
        pieces += d.piece[i];
    }
    std::printf(
        "\"%s\": {\"points\": %zu, \"position_sum\": [%.9g, %.9g, %.9g], \"velocity_sum\": [%.9g, %.9g, %.9g], "
        "\"pscale_sum\": %.9g, \"id_sum\": %lld, \"piece_sum\": %lld}",
        path, d.size(), position[0], position[1], position[2], velocity[0], velocity[1],
        velocity[2], pscale, static_cast<long long>(ids), static_cast<long long>(pieces));
}

// the piece keys of a mesh file's faces (nothing when it has no fragment ids)
void print_piece_info(const std::vector<TriMesh>& meshes) {
    std::set<int32_t> ids;
    int64_t face_sum = 0;
    for (const TriMesh& m : meshes)
        for (int32_t piece : m.face_fragment) {
            ids.insert(piece);
            face_sum += piece;
        }
    if (ids.empty()) return;
    int64_t id_sum = 0;
    for (int32_t piece : ids) id_sum += piece;
    std::printf(", \"pieces\": %zu, \"piece_id_sum\": %lld, \"piece_face_sum\": %lld", ids.size(),
                static_cast<long long>(id_sum), static_cast<long long>(face_sum));
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 2) {
        std::fprintf(stderr, "usage: blender_test_mesh_info FILE...\n");
        return 2;
    }
    std::printf("{");
    for (int i = 1; i < argc; ++i) {
        if (is_debris_file(argv[i])) {
            std::printf("%s\n", i > 1 ? "," : "");
            try {
                print_debris_info(argv[i]);
            } catch (const std::exception& e) {
                std::fprintf(stderr, "blender_test_mesh_info: %s\n", e.what());
                return 1;
            }
            continue;
        }
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
            colors = colors && m.saturation.size() == m.positions.size() &&
                     m.alpha.size() == m.positions.size();
            for (const Vec3f& p : m.positions)
                for (int k = 0; k < 3; ++k) sum[k] += p[k];
        }
        std::printf(
            "%s\n\"%s\": {\"vertices\": %zu, \"faces\": %zu, \"normals\": %s, \"uvs\": %s, \"colors\": %s, "
            "\"position_sum\": [%.9g, %.9g, %.9g]",
            i > 1 ? "," : "", argv[i], vertices, faces, normals ? "true" : "false",
            uvs ? "true" : "false", colors ? "true" : "false", sum[0], sum[1], sum[2]);
        if (!meshes.empty() && !meshes[0].positions.empty()) {
            const TriMesh& m = meshes[0];
            if (uvs) std::printf(", \"uv0\": [%.9g, %.9g]", m.uvs[0].x(), m.uvs[0].y());
            if (colors)
                std::printf(", \"color0\": [%.9g, %.9g]", m.saturation[0],
                            1.0 / (1.0 + std::exp(-double(m.alpha[0]))));
        }
        print_piece_info(meshes);
        std::printf("}");
    }
    std::printf("\n}\n");
    return 0;
}
