#pragma once
/// Wall-clock timing and memory, for stage summaries, manifests and bytes-per-particle reports.
#include <chrono>
#include <cstdint>
#include <vector>

namespace mudcrack {

class WallTimer {
public:
    WallTimer() : m_start(std::chrono::steady_clock::now()) {}
    /// Seconds since construction or the last reset().
    double seconds() const {
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - m_start).count();
    }
    void reset() { m_start = std::chrono::steady_clock::now(); }

private:
    std::chrono::steady_clock::time_point m_start;
};

/// Peak resident set size of this process so far [bytes].
int64_t peak_rss_bytes();

/// Bytes a vector holds: its capacity, not its size [bytes].
template <class T>
int64_t capacity_bytes(const std::vector<T>& v) {
    return static_cast<int64_t>(v.capacity() * sizeof(T));
}

}  // namespace mudcrack
