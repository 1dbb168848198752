#include "pipeline/io/checksum.h"

#include <immintrin.h>
#include <zlib.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>
#include <vector>

#include "sim/core/error.h"

namespace mudcrack {
namespace {

constexpr size_t kFoldMinimum = 64;  // the folding below starts with four 16-byte lanes

#define MC_CARRYLESS __attribute__((target("pclmul,sse4.1")))

MC_CARRYLESS inline __m128i load16(const unsigned char* p) {
    return _mm_loadu_si128(reinterpret_cast<const __m128i*>(p));
}

// x.hi * k.hi ^ x.lo * k.lo ^ next: 128 bits folded forward onto the next 128
MC_CARRYLESS inline __m128i fold16(__m128i x, __m128i k, __m128i next) {
    return _mm_xor_si128(
        _mm_xor_si128(_mm_clmulepi64_si128(x, k, 0x11), _mm_clmulepi64_si128(x, k, 0x00)), next);
}

/// CRC-32 folding with carry-less multiplication (Gopal et al., "Fast CRC Computation for Generic
/// Polynomials Using PCLMULQDQ Instruction", Intel 2009; the constants are that paper's for the
/// bit-reflected gzip polynomial, as in Linux's crc32-pclmul and Chromium's zlib): about ten
/// times zlib's table-driven speed, which keeps verification a small share of a stage that reads
/// gigabytes. `len` is a multiple of 16, at least 64; `crc` and the result are the raw register
/// (pre- and post-inverted by the caller).
MC_CARRYLESS uint32_t crc32_fold(const unsigned char* buf, size_t len, uint32_t crc) {
    alignas(16) static const uint64_t k1k2[] = {0x0154442bd4, 0x01c6e41596};
    alignas(16) static const uint64_t k3k4[] = {0x01751997d0, 0x00ccaa009e};
    alignas(16) static const uint64_t k5k0[] = {0x0163cd6124, 0x0000000000};
    alignas(16) static const uint64_t poly[] = {0x01db710641, 0x01f7011641};
    __m128i x1 = _mm_xor_si128(load16(buf), _mm_cvtsi32_si128(int(crc)));
    __m128i x2 = load16(buf + 16), x3 = load16(buf + 32), x4 = load16(buf + 48);
    buf += 64;
    len -= 64;
    // four lanes in parallel, 64 bytes a step
    __m128i k = _mm_load_si128(reinterpret_cast<const __m128i*>(k1k2));
    for (; len >= 64; buf += 64, len -= 64) {
        x1 = fold16(x1, k, load16(buf));
        x2 = fold16(x2, k, load16(buf + 16));
        x3 = fold16(x3, k, load16(buf + 32));
        x4 = fold16(x4, k, load16(buf + 48));
    }
    // the lanes into one, then the remaining 16-byte blocks
    k = _mm_load_si128(reinterpret_cast<const __m128i*>(k3k4));
    x1 = fold16(fold16(fold16(x1, k, x2), k, x3), k, x4);
    for (; len >= 16; buf += 16, len -= 16) x1 = fold16(x1, k, load16(buf));
    // 128 bits to 64, then a Barrett reduction to 32
    const __m128i low32 = _mm_setr_epi32(~0, 0, ~0, 0);
    x1 = _mm_xor_si128(_mm_srli_si128(x1, 8), _mm_clmulepi64_si128(x1, k, 0x10));
    k = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(k5k0));
    x1 = _mm_xor_si128(_mm_clmulepi64_si128(_mm_and_si128(x1, low32), k, 0x00),
                       _mm_srli_si128(x1, 4));
    k = _mm_load_si128(reinterpret_cast<const __m128i*>(poly));
    __m128i x5 = _mm_clmulepi64_si128(_mm_and_si128(x1, low32), k, 0x10);
    x5 = _mm_clmulepi64_si128(_mm_and_si128(x5, low32), k, 0x00);
    return uint32_t(_mm_extract_epi32(_mm_xor_si128(x1, x5), 1));
}

#undef MC_CARRYLESS

bool has_carryless_multiply() {
    static const bool has = __builtin_cpu_supports("pclmul") && __builtin_cpu_supports("sse4.1");
    return has;
}

}  // namespace

uint32_t crc32_update(uint32_t crc, const void* data, size_t size) {
    const auto* bytes = static_cast<const unsigned char*>(data);
    if (size >= kFoldMinimum && has_carryless_multiply()) {
        const size_t folded = size & ~size_t(15);
        crc = ~crc32_fold(bytes, folded, ~crc);
        bytes += folded;
        size -= folded;
    }
    return uint32_t(crc32(crc, bytes, uInt(size)));  // zlib's: the tail, or a machine without it
}

std::string file_crc32(const std::filesystem::path& file) {
    constexpr size_t kBlock = size_t(1) << 20;  // large enough that the read calls cost nothing
    const std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(file.c_str(), "rb"),
                                                            &std::fclose);
    if (!f) throw InputError(file.string() + ": cannot read: " + std::strerror(errno));
    std::vector<unsigned char> block(kBlock);
    uint32_t crc = 0;
    size_t got = 0;
    while ((got = std::fread(block.data(), 1, block.size(), f.get())) > 0)
        crc = crc32_update(crc, block.data(), got);
    if (std::ferror(f.get()))
        throw InputError(file.string() + ": cannot read: " + std::strerror(errno));
    char hex[16];
    std::snprintf(hex, sizeof hex, "%08x", crc);
    return hex;
}

}  // namespace mudcrack
