#pragma once
/// FNV-1a 64-bit: a tiny, dependency-free checksum for our own binary formats (checkpoints) and for
/// the content-derived UUID of points files. Not cryptographic; it detects truncation and bit rot.
#include <cstddef>
#include <cstdint>

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

}  // namespace mudcrack
