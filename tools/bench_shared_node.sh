#!/usr/bin/env bash
# mc-sim on a shared node: the demo shot's first frames on 2 threads, (a) alone and
# (b) beside a competing CPU-bound load (2 busy-looping processes, one per core), alternated PAIRS
# times. Prints every run, the medians, and (b)/(a): a fair share of the 2 cores gives 2, while
# OpenMP threads that spin at barriers make it many times that. Given a second build, the two
# builds alternate inside every pair and it also prints the quiet time ratio BUILD / OTHER_BUILD.
#
#   tools/bench_shared_node.sh [--frames A-B] [--pairs N] [--threads N] BUILD [OTHER_BUILD]
#       defaults: --frames 1-6 --pairs 3 --threads 2
#
# The stages run with the environment's OpenMP settings removed (OMP_WAIT_POLICY, GOMP_SPINCOUNT),
# so each build runs with its own defaults. Run it under `nice` to share a machine politely: the
# competing load inherits the same niceness, so the contest stays even. The load average at the
# start and end is printed: other jobs on the machine add to both (a) and (b).
set -euo pipefail

ROOT=$(cd "$(dirname "$0")/.." && pwd)
FRAMES=1-6 PAIRS=3 THREADS=2
BUILDS=()
while [[ $# -gt 0 ]]; do
    case $1 in
        --frames) FRAMES=$2; shift 2 ;;
        --pairs) PAIRS=$2; shift 2 ;;
        --threads) THREADS=$2; shift 2 ;;
        -h|--help) sed -n '2,15p' "$0"; exit 0 ;;
        -*) echo "bench_shared_node.sh: unknown option $1 (see --help)" >&2; exit 2 ;;
        *) BUILDS+=("$1"); shift ;;
    esac
done
[[ ${#BUILDS[@]} -ge 1 && ${#BUILDS[@]} -le 2 ]] || { echo "usage: $0 [--frames A-B] [--pairs N] [--threads N] BUILD [OTHER_BUILD]" >&2; exit 2; }
for b in "${BUILDS[@]}"; do
    for exe in mc-init mc-sim; do
        [[ -x $b/bin/$exe ]] || { echo "bench_shared_node.sh: $b/bin/$exe is not built" >&2; exit 1; }
    done
done
SHOT=$ROOT/shots/demo.json
TMP=$(mktemp -d /tmp/mudcrack_shared_node.XXXXXX)
LOAD_PIDS=()
stop_load() {
    for pid in "${LOAD_PIDS[@]}"; do kill "$pid" 2>/dev/null || true; done
    for pid in "${LOAD_PIDS[@]}"; do wait "$pid" 2>/dev/null || true; done
    LOAD_PIDS=()
}
trap 'stop_load; rm -rf "$TMP"' EXIT

# the stages with the caller's OpenMP wait settings removed
stage() { env -u OMP_WAIT_POLICY -u GOMP_SPINCOUNT "$@"; }

# the competing load: one busy loop per thread the sim uses
start_load() {
    for ((k = 0; k < THREADS; ++k)); do
        bash -c 'while :; do :; done' &
        LOAD_PIDS+=($!)
    done
}

# seconds of wall time of one mc-sim run of build $1 into its own output folder
sim_seconds() {
    local build=$1 out=$TMP/out.$2
    local t0 t1
    t0=$(date +%s.%N)
    stage "$build/bin/mc-sim" --quiet --threads "$THREADS" --frames "$FRAMES" --shot "$SHOT" --out "$out" >/dev/null
    t1=$(date +%s.%N)
    awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.3f", b - a }'
}
median() { sort -g | awk '{ v[NR] = $1 } END { print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }'; }

echo "load average at start: $(cut -d' ' -f1-3 /proc/loadavg); frames $FRAMES, $THREADS threads, $PAIRS pairs"
for i in "${!BUILDS[@]}"; do
    stage "${BUILDS[$i]}/bin/mc-init" --quiet --shot "$SHOT" --out "$TMP/out.$i" >/dev/null
done

declare -A QUIET LOADED
printf '%-5s %-40s %10s %10s %8s\n' pair build "quiet [s]" "loaded [s]" ratio
for ((p = 1; p <= PAIRS; ++p)); do
    for i in "${!BUILDS[@]}"; do
        q=$(sim_seconds "${BUILDS[$i]}" "$i")
        start_load
        l=$(sim_seconds "${BUILDS[$i]}" "$i")
        stop_load
        QUIET[$i]+="$q "
        LOADED[$i]+="$l "
        awk -v p="$p" -v b="${BUILDS[$i]}" -v q="$q" -v l="$l" 'BEGIN { printf "%-5s %-40s %10.2f %10.2f %8.2f\n", p, b, q, l, l / q }'
    done
done
for i in "${!BUILDS[@]}"; do
    mq=$(tr ' ' '\n' <<<"${QUIET[$i]}" | grep . | median)
    ml=$(tr ' ' '\n' <<<"${LOADED[$i]}" | grep . | median)
    awk -v b="${BUILDS[$i]}" -v q="$mq" -v l="$ml" \
        'BEGIN { printf "%-5s %-40s %10.2f %10.2f %8.2f  (loaded / quiet; a fair share is 2)\n", "median", b, q, l, l / q }'
done
if [[ ${#BUILDS[@]} -eq 2 ]]; then
    # quiet time of BUILD over OTHER_BUILD, pair by pair (the builds alternate inside each pair)
    read -r -a q0 <<<"${QUIET[0]}"
    read -r -a q1 <<<"${QUIET[1]}"
    ratios=()
    for ((p = 0; p < PAIRS; ++p)); do ratios+=("$(awk -v a="${q0[$p]}" -v b="${q1[$p]}" 'BEGIN { print a / b }')"); done
    echo "quiet time ${BUILDS[0]} / ${BUILDS[1]} per pair: ${ratios[*]}; median $(printf '%s\n' "${ratios[@]}" | median)"
fi
echo "load average at end: $(cut -d' ' -f1-3 /proc/loadavg)"
