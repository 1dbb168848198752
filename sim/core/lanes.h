#pragma once
/// Four doubles side by side (GCC's vector extension: one AVX register where the CPU has AVX,
/// two SSE2 ones or four scalars elsewhere), for the per-particle kernels that G2P runs on four
/// particles at once. Arithmetic is elementwise with IEEE rounding per lane, so a kernel written
/// once over `Lanes` and once over `Real` in the same order of operations gives the same bits in
/// every lane as the scalar one does (the tests compare them bit for bit).
#include <cstdint>
#include <cstring>

#include "sim/core/types.h"

namespace mudcrack {

constexpr int kLaneCount = 4;

/// Four doubles. + - * / act per lane; `a < b` gives a LaneMask (all ones where true).
using Lanes = Real __attribute__((vector_size(kLaneCount * sizeof(Real))));
/// Per-lane masks and integer bits, as comparisons of Lanes give them.
using LaneMask = int64_t __attribute__((vector_size(kLaneCount * sizeof(int64_t))));
using LaneBits = uint64_t __attribute__((vector_size(kLaneCount * sizeof(uint64_t))));

/// x in every lane (T = Real: x itself), for templates written once for Real and Lanes.
template <class T>
inline T splat(Real x) {
    if constexpr (!std::is_same_v<T, Real>)
        return Lanes{x, x, x, x};
    else
        return x;
}

/// A 3x3 matrix of Lanes (four matrices side by side), column-major as Mat3.
struct LaneMat3 {
    Lanes m[9];
    Lanes& operator()(int i, int j) { return m[i + 3 * j]; }
    const Lanes& operator()(int i, int j) const { return m[i + 3 * j]; }
};

/// The bits of x's lanes, and the lanes of bits (a vector cast reinterprets, as a union would).
inline LaneBits lanes_to_bits(Lanes x) { return (LaneBits)x; }
inline Lanes lanes_from_bits(LaneBits bits) { return (Lanes)bits; }

/// Lanes from four consecutive Reals, and back (one vector load or store).
inline Lanes lanes_load(const Real* x) {
    Lanes r;
    std::memcpy(&r, x, sizeof r);
    return r;
}
inline void lanes_store(Real* x, Lanes value) { std::memcpy(x, &value, sizeof value); }

/// Where mask is set, a; elsewhere b.
inline Lanes lanes_select(LaneMask mask, Lanes a, Lanes b) { return mask ? a : b; }

/// Whether every lane of mask is set.
inline bool lanes_all(LaneMask mask) { return (mask[0] & mask[1] & mask[2] & mask[3]) != 0; }

}  // namespace mudcrack
