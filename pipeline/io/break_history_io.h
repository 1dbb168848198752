#pragma once
/// surface/edge_breaks.bin: the first frame at which each tet edge broke (Eq. 14's "t <= n"),
/// computed once by mc-surface over all cached frames so frames can be surfaced in any order,
/// and read back by mc-measure. A cache: a stale or damaged file reads as "absent".
#include <cstdint>
#include <filesystem>
#include <optional>
#include <vector>

namespace mudcrack {

constexpr const char* kBreakHistoryFile = "edge_breaks.bin";

struct BreakHistory {
    // hash of what it was computed from (sim manifest, Eq. 14 parameters, mesh)
    uint64_t source_hash = 0;
    int32_t first_frame = 0, last_frame = 0;
    std::vector<int32_t> first_break;  // per edge; kNeverBroken (surfacing/edge_breaks.h) if never
};

/// Writes atomically (temporary name, then rename), with a checksum of first_break.
void write_break_history(const std::filesystem::path& path, const BreakHistory& history);

/// The stored history if the file is intact, holds n_edges edges and, when `source_hash` is
/// given, was computed from the same inputs; nullopt otherwise.
std::optional<BreakHistory> read_break_history(const std::filesystem::path& path,
                                               std::optional<uint64_t> source_hash,
                                               int64_t n_edges);

}  // namespace mudcrack
