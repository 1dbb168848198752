#!/usr/bin/env bash
# Peak memory of surfacing one frame, per output triangle: runs mc-surface on FRAME of a shot that
# has been simulated (OUT/init and OUT/sim exist) under /usr/bin/time, in a scratch folder that links
# OUT's init and sim (OUT/surface is not touched), and prints one table row per format.
#
#   tools/surface_memory.sh SHOT OUT FRAME [FORMAT...]   (default format: the shot's)
#
# e.g. tools/surface_memory.sh shots/fig6_eps_0.2.json out/fig6_eps_0.2 24 glb obj
# Environment: BUILD (default build), THREADS (default 2), MODE (a surfacing mode, default the shot's).
# Columns: triangles = boundary + crack faces written; peak = the process's maximum resident set;
# topology = the once-per-mesh surfacing topology (its manifest's topology_bytes); B/tri = (peak -
# topology) / triangles, the figure the production-scale issue bounds (~250); file = bytes written.
set -euo pipefail

ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${BUILD:-$ROOT/build}
THREADS=${THREADS:-2}
MODE=${MODE:-}
[[ $# -ge 3 ]] || { echo "usage: tools/surface_memory.sh SHOT OUT FRAME [FORMAT...]" >&2; exit 2; }
SHOT=$1 OUT=$2 FRAME=$3
shift 3
FORMATS=("$@")
[[ -f $SHOT ]] || { echo "surface_memory.sh: $SHOT: no such shot file" >&2; exit 1; }
[[ -f $OUT/sim/manifest.json ]] || { echo "surface_memory.sh: $OUT/sim/manifest.json: not found: simulate the shot first" >&2; exit 1; }
[[ $FRAME =~ ^[0-9]+$ ]] || { echo "surface_memory.sh: frame '$FRAME' is not a frame number" >&2; exit 1; }
[[ -x $BUILD/bin/mc-surface ]] || { echo "surface_memory.sh: $BUILD/bin/mc-surface is not built: run make build" >&2; exit 1; }
[[ -x /usr/bin/time ]] || { echo "surface_memory.sh: /usr/bin/time not found (make deps installs it)" >&2; exit 1; }
command -v jq >/dev/null || { echo "surface_memory.sh: jq not found (make deps installs it)" >&2; exit 1; }
[[ ${#FORMATS[@]} -gt 0 ]] || FORMATS=("")

WORK=$(mktemp -d "${TMPDIR:-/tmp}/surface_memory.XXXXXX")
trap 'rm -rf "$WORK"' EXIT
ln -s "$(cd "$OUT" && pwd)/init" "$WORK/init"
ln -s "$(cd "$OUT" && pwd)/sim" "$WORK/sim"

printf '%-6s %5s %11s %9s %9s %7s %9s %7s\n' format frame triangles "peak MB" "topo MB" B/tri "file MB" wall
for format in "${FORMATS[@]}"; do
    rm -rf "$WORK/surface"
    start=$(date +%s.%N)
    /usr/bin/time -f %M -o "$WORK/peak_kb" "$BUILD/bin/mc-surface" --shot "$SHOT" --out "$WORK" --threads "$THREADS" \
        --frames "$FRAME" ${format:+--format "$format"} ${MODE:+--mode "$MODE"} --quiet >"$WORK/log" 2>&1 ||
        { echo "surface_memory.sh: mc-surface failed:" >&2; tail -5 "$WORK/log" >&2; exit 1; }
    wall=$(awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f", b - a }')
    m=$WORK/surface/manifest.json
    read -r fmt tris topo < <(jq -r '[.format, (.per_frame[0] | .boundary.faces + (.crack.faces // 0)), .topology_bytes] | @tsv' "$m")
    files=$(jq -r '.per_frame[0] | [.boundary.file, (.crack.file // empty)] | .[]' "$m")
    bytes=0
    for f in $files; do bytes=$((bytes + $(stat -c %s "$WORK/surface/$f"))); done
    peak=$(($(cat "$WORK/peak_kb") * 1024))
    awk -v f="$fmt" -v n="$FRAME" -v t="$tris" -v p="$peak" -v g="$topo" -v b="$bytes" -v w="$wall" 'BEGIN {
        printf "%-6s %5d %11d %9.0f %9.0f %7.0f %9.0f %6ss\n", f, n, t, p / 1e6, g / 1e6, (t > 0 ? (p - g) / t : 0), b / 1e6, w }'
done
