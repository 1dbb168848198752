#!/usr/bin/env bash
# Two builds' stage programs on one shot's outputs, alternated: one run of OLD_BUILD's mc-STAGE
# then one of NEW_BUILD's, PAIRS times per stage, so a machine whose speed drifts (or another job
# on it) weighs on both alike. Prints each pair's seconds per frame (wall) and the ratios new/old
# of wall and CPU (user + system) time, then their medians. Made to price a change inside a
# stage's reading or writing, such as checking the files it reads against their checksums.
#
#   tools/bench_stage_compare.sh [--pairs N] [--threads N] [--frames A-B] OLD_BUILD NEW_BUILD SHOT OUT STAGE...
#       defaults: --pairs 3 --threads 2 --frames 1-2; STAGE is surface or render
#
# OUT must already hold what the first stage reads (init/ and sim/ for surface) for the frames
# asked; it is read, never written. Each build writes into its own output root in a temporary
# folder, where OUT's stage folders appear as links (readers follow them), so a later stage reads
# what the same build's earlier stage wrote: give the stages in order ("surface render"; a build
# refuses another version's surface/ when its shot slice differs). Before every run the stage's
# folder is removed, so each run writes it afresh; render runs as a --frames chunk (its frames
# only: no turntable, movie or contact sheet). Each build's stage starts with one untimed run,
# which warms the page cache. A ratio of 1.02 means the new build's stage takes 2 % more time.
set -euo pipefail

PAIRS=3 THREADS=2 FRAMES=1-2
ARGS=()
while [[ $# -gt 0 ]]; do
    case $1 in
        --pairs) PAIRS=$2; shift 2 ;;
        --threads) THREADS=$2; shift 2 ;;
        --frames) FRAMES=$2; shift 2 ;;
        -h|--help) sed -n '2,18p' "$0"; exit 0 ;;
        -*) echo "bench_stage_compare.sh: unknown option $1 (see --help)" >&2; exit 2 ;;
        *) ARGS+=("$1"); shift ;;
    esac
done
[[ ${#ARGS[@]} -ge 5 ]] || {
    echo "usage: $0 [--pairs N] [--threads N] [--frames A-B] OLD_BUILD NEW_BUILD SHOT OUT STAGE..." >&2
    exit 2
}
OLD=${ARGS[0]} NEW=${ARGS[1]} SHOT=${ARGS[2]} OUT=${ARGS[3]}
STAGES=("${ARGS[@]:4}")
for stage in "${STAGES[@]}"; do
    [[ $stage == surface || $stage == render ]] || { echo "bench_stage_compare.sh: stage $stage: expected surface or render" >&2; exit 2; }
    for b in "$OLD" "$NEW"; do
        [[ -x $b/bin/mc-$stage ]] || { echo "bench_stage_compare.sh: $b/bin/mc-$stage is not built" >&2; exit 1; }
    done
done
[[ $FRAMES =~ ^([0-9]+)-([0-9]+)$ ]] || { echo "bench_stage_compare.sh: --frames $FRAMES: expected A-B" >&2; exit 2; }
N_FRAMES=$((BASH_REMATCH[2] - BASH_REMATCH[1] + 1))

# each build's output root: OUT's stage folders as links, the stages' own folders written there
TMP=$(mktemp -d /tmp/mudcrack_stage_compare.XXXXXX)
trap 'rm -rf "$TMP"' EXIT
for side in old new; do
    mkdir -p "$TMP/$side"
    for dir in "$OUT"/*/; do
        name=$(basename "$dir")
        [[ " ${STAGES[*]} " == *" $name "* ]] || ln -s "$(cd "$dir" && pwd)" "$TMP/$side/$name"
    done
done

# one run of a build's stage into its root -> "wall-seconds cpu-seconds" ("" on failure)
run() {
    local build=$1 root=$2 stage=$3 times=$TMP/times
    rm -rf "${root:?}/$stage"
    /usr/bin/time -f '%e %U %S' -o "$times" "$build/bin/mc-$stage" --shot "$SHOT" --out "$root" \
        --threads "$THREADS" --frames "$FRAMES" --quiet >/dev/null 2>"$times.err" ||
        { echo "bench_stage_compare.sh: $build/bin/mc-$stage failed:" >&2; cat "$times.err" >&2; return 0; }
    awk '{ print $1, $2 + $3 }' "$times"
}
median() { sort -g | awk '{ v[NR] = $1 } END { print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }'; }

echo "load average at start: $(cut -d' ' -f1-3 /proc/loadavg)"
echo "frames $FRAMES, $THREADS threads, $PAIRS pairs; seconds per frame and new/old ratios"
printf '%-8s %-7s %-12s %-12s %-12s %s\n' stage pair "old [s/f]" "new [s/f]" "wall ratio" "CPU ratio"
for stage in "${STAGES[@]}"; do
    # warm-up
    [[ -n $(run "$OLD" "$TMP/old" "$stage") && -n $(run "$NEW" "$TMP/new" "$stage") ]] || exit 1
    wall=() cpu=()
    for ((i = 1; i <= PAIRS; ++i)); do
        read -r ow oc <<<"$(run "$OLD" "$TMP/old" "$stage")"
        read -r nw nc <<<"$(run "$NEW" "$TMP/new" "$stage")"
        [[ -n ${ow:-} && -n ${nw:-} ]] || exit 1
        wall+=("$(awk -v o="$ow" -v n="$nw" 'BEGIN { print n / o }')")
        cpu+=("$(awk -v o="$oc" -v n="$nc" 'BEGIN { print n / o }')")
        awk -v s="$stage" -v i="$i" -v ow="$ow" -v nw="$nw" -v oc="$oc" -v nc="$nc" -v f="$N_FRAMES" \
            'BEGIN { printf "%-8s %-7s %-12.2f %-12.2f %-12.3f %.3f\n", s, i, ow / f, nw / f, nw / ow, nc / oc }'
    done
    printf '%-8s %-7s %-12s %-12s %-12.3f %.3f\n' "$stage" median "" "" \
        "$(printf '%s\n' "${wall[@]}" | median)" "$(printf '%s\n' "${cpu[@]}" | median)"
done
echo "load average at end: $(cut -d' ' -f1-3 /proc/loadavg)"
