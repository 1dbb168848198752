#!/usr/bin/env bash
# Moisture's cost on the simulation benchmarks' reference scene (tests/mpm/mpm_bench.cpp): NACC
# alone and NACC + moisture run alternately, one 404-step run each, PAIRS pairs per thread count, so
# a VM whose speed drifts between runs (by a few % here) weighs on both configurations alike. Prints
# each pair's particle-steps/s and time ratio, then the medians.
#
#   tools/bench_moisture_cost.sh [BUILD_DIR] [PAIRS] [THREADS...]   (default: build 5 1 2)
#
# The time ratio is moisture's step time over NACC's: 1.30 means moisture costs 30 % more time,
# i.e. 23 % fewer particle-steps per second.
set -euo pipefail

ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${1:-$ROOT/build}
PAIRS=${2:-5}
shift $(( $# < 2 ? $# : 2 ))
THREADS=("$@")
[[ ${#THREADS[@]} -gt 0 ]] || THREADS=(1 2)
BENCH=$BUILD/bin/mpm_bench
[[ -x $BENCH ]] || { echo "bench_moisture_cost.sh: $BENCH is not built: run make bench" >&2; exit 1; }

# one run of a configuration on a thread count -> its particle-steps/s
rate() {
    MUDCRACK_BENCH_REPETITIONS=1 "$BENCH" --benchmark_filter="^BM_ReferenceScene/$1/$2/" \
        --benchmark_format=csv 2>/dev/null |
        awk -F, 'NR == 1 { for (i = 1; i <= NF; ++i) if ($i == "\"particle_steps_per_s\"") c = i }
                 NR == 2 && c { print $c }'
}
median() { sort -g | awk '{ v[NR] = $1 } END { print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }'; }

printf '%-8s %-5s %-24s %-24s %s\n' threads pair "NACC [M p-steps/s]" "NACC+moisture [M/s]" "time ratio"
for t in "${THREADS[@]}"; do
    nacc=() moist=() ratio=()
    for ((i = 1; i <= PAIRS; ++i)); do
        a=$(rate NoMoisture "$t")
        b=$(rate Moisture "$t")
        [[ -n $a && -n $b ]] || { echo "bench_moisture_cost.sh: $BENCH printed no particle_steps_per_s" >&2; exit 1; }
        nacc+=("$a") moist+=("$b") ratio+=("$(awk -v a="$a" -v b="$b" 'BEGIN { print a / b }')")
        awk -v t="$t" -v i="$i" -v a="$a" -v b="$b" \
            'BEGIN { printf "%-8s %-5s %-24.3f %-24.3f %.3f\n", t, i, a / 1e6, b / 1e6, a / b }'
    done
    ma=$(printf '%s\n' "${nacc[@]}" | median)
    mb=$(printf '%s\n' "${moist[@]}" | median)
    mr=$(printf '%s\n' "${ratio[@]}" | median)
    awk -v t="$t" -v a="$ma" -v b="$mb" -v r="$mr" \
        'BEGIN { printf "%-8s %-5s %-24.3f %-24.3f %.3f  (+%.0f %% time, -%.0f %% particle-steps/s)\n",
                 t, "median", a / 1e6, b / 1e6, r, 100 * (r - 1), 100 * (1 - 1 / r) }'
done
