#pragma once
/// Full-precision restart files for the simulation: a small, versioned, little-endian binary
/// format holding named arrays and scalars, so io does not depend on sim/ (the sim stage maps
/// SimState to and from a Checkpoint).
///
/// Layout (all integers little-endian):
///   magic     8 bytes  "MCCKPT1\0"
///   version   uint32   kCheckpointFormatVersion
///   count     uint32   number of entries
///   entries   count x { kind uint8, name_len uint32, name bytes (UTF-8),
///                       n uint64 (elements; bytes for a string; 1 for a scalar),
///                       n x element bytes }
///             kinds: 1 float64[], 2 int32[], 3 int64[], 4 string, 5 float64, 6 int64;
///             written kind by kind, each sorted by name (deterministic bytes)
///   checksum  uint64   FNV-1a 64 of every byte before it (detects truncation and corruption)
#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace mudcrack {

constexpr uint32_t kCheckpointFormatVersion = 1;

/// Named arrays and scalars. Names are unique within a kind.
struct Checkpoint {
    std::map<std::string, std::vector<double>> f64;   // e.g. "x" (3 n_particles), "Fe" (9 n)
    std::map<std::string, std::vector<int32_t>> i32;  // e.g. "id"
    std::map<std::string, std::vector<int64_t>> i64;
    std::map<std::string, std::string> meta_string;  // e.g. "stage", "shot_hash"
    std::map<std::string, double> meta_double;       // e.g. "time" [s]
    std::map<std::string, int64_t> meta_int;         // e.g. "frame", "step"
    std::string source;                              // the file it was read from (for messages)

    /// The named array; throws InputError naming `source` and the name when it is missing or
    /// its length is not `expected_size` (pass SIZE_MAX to accept any length).
    const std::vector<double>& require_f64(const std::string& name,
                                           size_t expected_size = SIZE_MAX) const;
    const std::vector<int32_t>& require_i32(const std::string& name,
                                            size_t expected_size = SIZE_MAX) const;
    const std::vector<int64_t>& require_i64(const std::string& name,
                                            size_t expected_size = SIZE_MAX) const;
    /// The named scalar; throws InputError naming `source` and the name when it is missing.
    double require_double(const std::string& name) const;
    int64_t require_int(const std::string& name) const;
    const std::string& require_string(const std::string& name) const;
};

/// Writes `checkpoint` atomically (temporary name + rename). Identical content gives identical
/// bytes.
void write_checkpoint(const std::filesystem::path& path, const Checkpoint& checkpoint);

/// Reads a checkpoint; the result's `source` is `path`. Throws InputError naming the file when it
/// is missing, not a checkpoint, of another format version, truncated, or fails its checksum.
Checkpoint read_checkpoint(const std::filesystem::path& path);

}  // namespace mudcrack
