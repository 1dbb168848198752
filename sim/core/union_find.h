#pragma once
/// Disjoint sets over 0..n-1 (union-find with path halving). A union makes the smaller root the
/// parent, so every set's root is its smallest element: sets numbered in root order come out the
/// same whatever order the unions were made in, which keeps the callers deterministic.
#include <cstdint>
#include <numeric>
#include <utility>
#include <vector>

namespace mudcrack {

class UnionFind {
public:
    UnionFind() = default;
    explicit UnionFind(int32_t n) { reset(n); }

    /// n singletons 0..n-1, reusing the memory.
    void reset(int32_t n) {
        m_parent.resize(n);
        std::iota(m_parent.begin(), m_parent.end(), 0);
    }
    /// The root of a's set: its smallest element.
    int32_t find(int32_t a) {
        while (m_parent[a] != a) {
            m_parent[a] = m_parent[m_parent[a]];
            a = m_parent[a];
        }
        return a;
    }
    /// Joins the sets of a and b.
    void unite(int32_t a, int32_t b) {
        a = find(a);
        b = find(b);
        if (a == b) return;
        if (a > b) std::swap(a, b);
        m_parent[b] = a;
    }
    int32_t size() const { return static_cast<int32_t>(m_parent.size()); }

private:
    std::vector<int32_t> m_parent;
};

}  // namespace mudcrack
