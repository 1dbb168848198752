#pragma once
/// Threads hidden behind two calls (pbrt's ParallelFor) so kernels carry no pragmas.
/// Static scheduling: the same thread count always gives the same partition, which is what
/// makes caches bit-identical run to run.
#include <cstdint>
#include <vector>

namespace mudcrack {

/// Sets the worker count for everything after it (0 = OpenMP's default).
void set_thread_count(int n);
/// The worker count parallel_for will use.
int thread_count();

/// Calls fn(i) for i in [0, n) on the worker threads, statically partitioned.
template <class Fn>
void parallel_for(int64_t n, Fn&& fn) {
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < n; ++i) fn(i);
}

/// Calls fn(chunk, begin, end) once per worker over a contiguous static split of [0, n);
/// chunk is in [0, thread_count()). For per-thread scratch summed in thread order.
template <class Fn>
void parallel_chunks(int64_t n, Fn&& fn) {
    const int nt = thread_count();
#pragma omp parallel for schedule(static, 1) num_threads(nt)
    for (int t = 0; t < nt; ++t) {
        const int64_t begin = n * t / nt, end = n * (t + 1) / nt;
        fn(t, begin, end);
    }
}

/// Deterministic reduction: per-chunk partials combined in chunk order.
template <class T, class Fn, class Combine>
T parallel_reduce(int64_t n, T identity, Fn&& fn, Combine&& combine) {
    std::vector<T> partial(thread_count(), identity);
    parallel_chunks(n, [&](int t, int64_t b, int64_t e) {
        T acc = identity;
        for (int64_t i = b; i < e; ++i) acc = combine(acc, fn(i));
        partial[t] = acc;
    });
    T acc = identity;
    for (const T& p : partial) acc = combine(acc, p);
    return acc;
}

}  // namespace mudcrack
