#!/usr/bin/env bash
# Two builds' step loop on the simulation benchmarks' reference scene (tests/mpm/mpm_bench.cpp),
# alternated: one run of OLD_BUILD's mpm_bench then one of NEW_BUILD's, PAIRS times per
# configuration, so a VM whose speed drifts (or another job on the machine) weighs on both alike.
# Prints each pair's particle-steps/s (wall, and per CPU second: what an idle machine would give on
# 1 thread) and the time ratio new/old, then the medians.
#
#   tools/bench_compare.sh OLD_BUILD NEW_BUILD [PAIRS] [CONFIG/THREADS[:CONFIG/THREADS]...]
#       default: 5 pairs of NoMoisture/1 Moisture/1 NoMoisture/2 Moisture/2
#
# A ratio of 1.02 means the new build's step takes 2 % more time.
# OLD_BENCH and NEW_BENCH (default BM_ReferenceScene) name each side's benchmark: a float state
# against a double one in the same build is
#   OLD_BENCH=BM_ReferenceScene NEW_BENCH=BM_ReferenceSceneFloat tools/bench_compare.sh build build 3
# A configuration OLD_CONFIG:NEW_CONFIG runs OLD_CONFIG on the old side and NEW_CONFIG on the new:
# how one build scales from 1 thread to 2 is
#   tools/bench_compare.sh build build 5 NoMoisture/1:NoMoisture/2
# (a time ratio of 0.52 there is a speed-up of 1 / 0.52 = 1.92x).
set -euo pipefail

[[ $# -ge 2 ]] || { echo "usage: $0 OLD_BUILD NEW_BUILD [PAIRS] [CONFIG/THREADS[:CONFIG/THREADS]...]" >&2; exit 2; }
OLD=$1/bin/mpm_bench
NEW=$2/bin/mpm_bench
PAIRS=${3:-5}
OLD_BENCH=${OLD_BENCH:-BM_ReferenceScene}
NEW_BENCH=${NEW_BENCH:-BM_ReferenceScene}
shift $(( $# < 3 ? $# : 3 ))
CONFIGS=("$@")
[[ ${#CONFIGS[@]} -gt 0 ]] || CONFIGS=(NoMoisture/1 Moisture/1 NoMoisture/2 Moisture/2)
for b in "$OLD" "$NEW"; do
    [[ -x $b ]] || { echo "bench_compare.sh: $b is not built" >&2; exit 1; }
done

# one run of a build's benchmark on a configuration -> "particle-steps/s particle-steps/CPU-s"
rates() {
    MUDCRACK_BENCH_REPETITIONS=1 "$1" --benchmark_filter="^$3/$2/" --benchmark_format=csv 2>/dev/null |
        awk -F, 'NR == 1 { for (i = 1; i <= NF; ++i) { if ($i == "\"particle_steps_per_s\"") w = i
                                                       if ($i == "\"particle_steps_per_cpu_s\"") c = i } }
                 NR == 2 && w && c { print $w, $c }'
}
median() { sort -g | awk '{ v[NR] = $1 } END { print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }'; }

echo "load average at start: $(cut -d' ' -f1-3 /proc/loadavg)"
printf '%-25s %-5s %-14s %-14s %-12s %-14s %-14s %s\n' config pair "old [M/s]" "new [M/s]" "time ratio" \
    "old [M/CPU-s]" "new [M/CPU-s]" "CPU ratio"
for config in "${CONFIGS[@]}"; do
    wall=() cpu=()
    for ((i = 1; i <= PAIRS; ++i)); do
        read -r ow oc <<<"$(rates "$OLD" "${config%%:*}" "$OLD_BENCH")"
        read -r nw nc <<<"$(rates "$NEW" "${config##*:}" "$NEW_BENCH")"
        [[ -n ${ow:-} && -n ${nw:-} ]] || { echo "bench_compare.sh: no particle_steps_per_s for $config" >&2; exit 1; }
        wall+=("$(awk -v o="$ow" -v n="$nw" 'BEGIN { print o / n }')")
        cpu+=("$(awk -v o="$oc" -v n="$nc" 'BEGIN { print o / n }')")
        awk -v c="$config" -v i="$i" -v ow="$ow" -v nw="$nw" -v oc="$oc" -v nc="$nc" \
            'BEGIN { printf "%-25s %-5s %-14.3f %-14.3f %-12.3f %-14.3f %-14.3f %.3f\n", c, i, ow / 1e6, nw / 1e6, ow / nw, oc / 1e6, nc / 1e6, oc / nc }'
    done
    printf '%-25s %-5s %-14s %-14s %-12.3f %-14s %-14s %.3f\n' "$config" median "" "" \
        "$(printf '%s\n' "${wall[@]}" | median)" "" "" "$(printf '%s\n' "${cpu[@]}" | median)"
done
echo "load average at end: $(cut -d' ' -f1-3 /proc/loadavg)"
