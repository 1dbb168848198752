#include "pipeline/io/tri_mesh_check.h"

#include <string>

#include "sim/core/error.h"

namespace fs = std::filesystem;

namespace mudcrack {

void check_tri_mesh(const fs::path& path, const TriMesh& m) {
    const size_t n = m.positions.size();
    auto check = [&](size_t size, const char* what) {
        if (size != 0 && size != n)
            throw RuntimeError(path.string() + ": mesh '" + m.name + "' has " +
                               std::to_string(size) + " " + what + " for " + std::to_string(n) +
                               " vertices");
    };
    check(m.normals.size(), "normals");
    check(m.uvs.size(), "uvs");
    check(m.saturation.size(), "saturation values");
    check(m.alpha.size(), "alpha values");
    if (!m.face_fragment.empty() && m.face_fragment.size() != m.faces.size())
        throw RuntimeError(path.string() + ": mesh '" + m.name + "' has " +
                           std::to_string(m.face_fragment.size()) + " fragment ids for " +
                           std::to_string(m.faces.size()) + " faces");
    for (size_t f = 0; f < m.faces.size(); ++f)
        for (int32_t v : m.faces[f])
            if (v < 0 || size_t(v) >= n)
                throw RuntimeError(path.string() + ": mesh '" + m.name + "' face " +
                                   std::to_string(f) + " references vertex " + std::to_string(v) +
                                   " of " + std::to_string(n));
}

}  // namespace mudcrack
