#pragma once
/// Fragment ids travel per vertex in the mesh files (UV channel 1), while TriMesh keeps them per
/// face. A vertex that faces of different fragments share needs one copy per extra fragment. The
/// surfacing never shares a vertex across fragments (a welded core vertex joins particles that
/// intact edges connect, which a fragment never separates), so the common case copies nothing:
/// this plan lists only the copies and the face corners that move to them, and writers read the
/// mesh through it instead of duplicating it.
#include <algorithm>
#include <climits>
#include <cstdint>
#include <utility>
#include <vector>

#include "sim/core/tri_mesh.h"

namespace mudcrack {

class FragmentSplit {
public:
    /// The plan for `mesh`; with no face_fragment, every vertex keeps fragment 0 and nothing
    /// splits.
    explicit FragmentSplit(const TriMesh& mesh);

    /// Vertices of the written mesh: the mesh's own, then the copies.
    int64_t vertex_count() const { return m_n_original + int64_t(m_copy_source.size()); }
    /// The mesh vertex whose attributes vertex v of the written mesh carries.
    int32_t source(int64_t v) const {
        return v < m_n_original ? int32_t(v) : m_copy_source[size_t(v - m_n_original)];
    }
    /// The fragment of vertex v of the written mesh (0 when the mesh has no fragment ids).
    int32_t fragment(int64_t v) const {
        return m_vertex_fragment.empty() ? 0 : m_vertex_fragment[size_t(v)];
    }
    bool has_fragments() const { return !m_vertex_fragment.empty(); }

    /// Face f with the written mesh's vertex ids.
    Tri face(const TriMesh& mesh, size_t f) const {
        Tri t = mesh.faces[f];
        if (m_moved_corner.empty()) return t;
        const int64_t first = 3 * int64_t(f);
        auto it = std::lower_bound(m_moved_corner.begin(), m_moved_corner.end(),
                                   std::make_pair(first, INT32_MIN));
        for (; it != m_moved_corner.end() && it->first < first + 3; ++it)
            t[it->first - first] = it->second;
        return t;
    }

private:
    int64_t m_n_original = 0;
    std::vector<int32_t> m_copy_source;      // mesh vertex of each copy
    std::vector<int32_t> m_vertex_fragment;  // per written vertex, or empty
    // (3 face + corner, copy), ascending
    std::vector<std::pair<int64_t, int32_t>> m_moved_corner;
};

}  // namespace mudcrack
