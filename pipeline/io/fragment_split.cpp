#include "pipeline/io/fragment_split.h"

#include <climits>
#include <map>

namespace mudcrack {

FragmentSplit::FragmentSplit(const TriMesh& mesh) : m_n_original(int64_t(mesh.positions.size())) {
    if (mesh.face_fragment.empty()) return;
    m_vertex_fragment.assign(mesh.positions.size(), INT32_MIN);
    // (vertex, fragment) -> copy; only shared vertices
    std::map<std::pair<int32_t, int32_t>, int32_t> copy_of;
    for (size_t f = 0; f < mesh.faces.size(); ++f) {
        const int32_t fragment = mesh.face_fragment[f];
        for (int c = 0; c < 3; ++c) {
            const int32_t v = mesh.faces[f][c];
            if (v < 0 || size_t(v) >= mesh.positions.size()) continue;  // the writers name bad ids
            if (m_vertex_fragment[v] == INT32_MIN) m_vertex_fragment[v] = fragment;
            if (m_vertex_fragment[v] == fragment) continue;
            auto [it, inserted] = copy_of.emplace(std::make_pair(v, fragment), 0);
            if (inserted) {
                it->second = int32_t(vertex_count());
                m_copy_source.push_back(v);
                m_vertex_fragment.push_back(fragment);
            }
            m_moved_corner.emplace_back(3 * int64_t(f) + c, it->second);
        }
    }
    // vertices no face uses keep fragment 0
    for (int32_t& fragment : m_vertex_fragment)
        if (fragment == INT32_MIN) fragment = 0;
}

}  // namespace mudcrack
