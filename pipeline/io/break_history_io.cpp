#include "pipeline/io/break_history_io.h"

#include <cerrno>
#include <cstring>
#include <fstream>

#include "pipeline/io/atomic_output.h"
#include "pipeline/io/checksum.h"
#include "sim/core/error.h"

namespace mudcrack {
namespace {
constexpr char kBreaksMagic[8] = {'M', 'C', 'B', 'R', 'K', 'v', '1', '\0'};
}  // namespace

void write_break_history(const std::filesystem::path& path, const BreakHistory& h) {
    write_atomically(path, [&](const std::filesystem::path& tmp) {
        errno = 0;
        std::ofstream out(tmp, std::ios::binary);
        if (!out)
            throw RuntimeError(tmp.string() + ": cannot open for writing: " + write_error_reason());
        const int64_t n = static_cast<int64_t>(h.first_break.size());
        const uint64_t checksum =
            fnv1a64(h.first_break.data(), h.first_break.size() * sizeof(int32_t));
        out.write(kBreaksMagic, sizeof kBreaksMagic);
        out.write(reinterpret_cast<const char*>(&h.source_hash), sizeof h.source_hash);
        out.write(reinterpret_cast<const char*>(&h.first_frame), sizeof h.first_frame);
        out.write(reinterpret_cast<const char*>(&h.last_frame), sizeof h.last_frame);
        out.write(reinterpret_cast<const char*>(&n), sizeof n);
        out.write(reinterpret_cast<const char*>(h.first_break.data()), n * sizeof(int32_t));
        out.write(reinterpret_cast<const char*>(&checksum), sizeof checksum);
        out.close();  // a small file fails only here, when its one buffer is flushed
        if (!out)
            throw RuntimeError(tmp.string() +
                               ": cannot write the edge break history: " + write_error_reason());
    });
}

std::optional<BreakHistory> read_break_history(const std::filesystem::path& path,
                                               std::optional<uint64_t> source_hash,
                                               int64_t n_edges) {
    std::ifstream in(path, std::ios::binary);
    if (!in) return std::nullopt;
    char magic[8];
    BreakHistory h;
    int64_t n = 0;
    in.read(magic, sizeof magic);
    in.read(reinterpret_cast<char*>(&h.source_hash), sizeof h.source_hash);
    in.read(reinterpret_cast<char*>(&h.first_frame), sizeof h.first_frame);
    in.read(reinterpret_cast<char*>(&h.last_frame), sizeof h.last_frame);
    in.read(reinterpret_cast<char*>(&n), sizeof n);
    if (!in || std::memcmp(magic, kBreaksMagic, sizeof magic) != 0 || n != n_edges ||
        (source_hash && h.source_hash != *source_hash))
        return std::nullopt;
    h.first_break.resize(n);
    uint64_t checksum = 0;
    in.read(reinterpret_cast<char*>(h.first_break.data()), n * sizeof(int32_t));
    in.read(reinterpret_cast<char*>(&checksum), sizeof checksum);
    if (!in || checksum != fnv1a64(h.first_break.data(), h.first_break.size() * sizeof(int32_t)))
        return std::nullopt;
    return h;
}

}  // namespace mudcrack
