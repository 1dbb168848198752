#pragma once
/// The two checksums of the pipeline, one job each. Neither is cryptographic; both detect
/// truncation and bit rot.
/// - FNV-1a 64: a tiny, dependency-free hash for our own binary formats (checkpoints, the break
///   history) and for the content-derived UUID of points files.
/// - CRC-32 of a whole file, recorded in the manifest that names the file (docs/architecture.md
///   §3): zlib's, the checksum of gzip and PNG, because every reader has it fast (C++ through the
///   processor's carry-less multiply, Python through zlib.crc32, the farm's scripts through
///   mc-shot verify), and a CRC-32 catches every error burst of up to 32 bits, so any single
///   flipped byte.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>

namespace mudcrack {

constexpr uint64_t kFnv1a64Offset = 14695981039346656037ull;
constexpr uint64_t kFnv1a64Prime = 1099511628211ull;

/// Continues an FNV-1a 64 hash over `size` bytes; start with `hash = kFnv1a64Offset`.
inline uint64_t fnv1a64(const void* data, size_t size, uint64_t hash = kFnv1a64Offset) {
    const auto* bytes = static_cast<const unsigned char*>(data);
    for (size_t i = 0; i < size; ++i) {
        hash ^= bytes[i];
        hash *= kFnv1a64Prime;
    }
    return hash;
}

/// The FNV-1a 64 hash of a string's bytes (the shot slices' hash).
inline uint64_t fnv1a64_of(const std::string& text) { return fnv1a64(text.data(), text.size()); }

/// Continues a CRC-32 (zlib's crc32: start with 0) over `size` bytes, with the processor's
/// carry-less multiply where it has one (x86-64 since 2010), else zlib's tables.
uint32_t crc32_update(uint32_t crc, const void* data, size_t size);

/// The CRC-32 of a file's bytes as 8 lowercase hex digits ("0a1b2c3d"), as Python's
/// f"{zlib.crc32(data):08x}" prints it. Throws InputError naming the file when it is missing or
/// cannot be read.
std::string file_crc32(const std::filesystem::path& file);

}  // namespace mudcrack
