#pragma once
/// Invariant checks for bugs (pbrt's CHECK_*): print both operands and abort. Bad input must
/// throw InputError instead. MC_DCHECK* compile out of Release builds (hot loops).
#include <cstdio>
#include <cstdlib>
#include <sstream>

#define MC_CHECK(cond)                                                                    \
    do {                                                                                  \
        if (!(cond)) {                                                                    \
            std::fprintf(stderr, "%s:%d: check failed: %s\n", __FILE__, __LINE__, #cond); \
            std::abort();                                                                 \
        }                                                                                 \
    } while (0)

#define MC_CHECK_OP(a, op, b)                                                                     \
    do {                                                                                          \
        const auto& mc_a_ = (a);                                                                  \
        const auto& mc_b_ = (b);                                                                  \
        if (!(mc_a_ op mc_b_)) {                                                                  \
            std::ostringstream mc_os_;                                                            \
            mc_os_ << __FILE__ << ":" << __LINE__ << ": check failed: " #a " " #op " " #b << " (" \
                   << mc_a_ << " vs " << mc_b_ << ")\n";                                          \
            std::fputs(mc_os_.str().c_str(), stderr);                                             \
            std::abort();                                                                         \
        }                                                                                         \
    } while (0)

#define MC_CHECK_EQ(a, b) MC_CHECK_OP(a, ==, b)
#define MC_CHECK_NE(a, b) MC_CHECK_OP(a, !=, b)
#define MC_CHECK_LT(a, b) MC_CHECK_OP(a, <, b)
#define MC_CHECK_LE(a, b) MC_CHECK_OP(a, <=, b)
#define MC_CHECK_GT(a, b) MC_CHECK_OP(a, >, b)
#define MC_CHECK_GE(a, b) MC_CHECK_OP(a, >=, b)

#ifdef NDEBUG
#define MC_DCHECK(cond) ((void)0)
#define MC_DCHECK_LT(a, b) ((void)0)
#define MC_DCHECK_LE(a, b) ((void)0)
#else
#define MC_DCHECK(cond) MC_CHECK(cond)
#define MC_DCHECK_LT(a, b) MC_CHECK_LT(a, b)
#define MC_DCHECK_LE(a, b) MC_CHECK_LE(a, b)
#endif
