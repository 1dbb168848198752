#!/usr/bin/env bash
# A close-up of one frame of a simulated shot, as a supervisor reviews it: surfaces FRAME in each
# surfacing MODE and renders it at 1600x900 from a fixed camera, changing only the shot's
# /surfacing/mode and render keys, in a scratch folder that links OUT's init and sim (OUT itself is
# not touched). Prints mc-measure's mesh figures for each mode.
#
#   tools/closeup.sh SHOT OUT FRAME DEST_PREFIX [MODE...]      (default modes: ours plates)
#
# e.g. tools/closeup.sh shots/demo.json out/demo 40 docs/closeups/demo ours plates
#      -> docs/closeups/demo_ours.png, docs/closeups/demo_plates.png
# Environment: BUILD (default build), THREADS (default 2), CAMERA (a JSON camera, default the
# demo's close-up: {"position": [0.55, 0.45, 0.6], "target": [0.05, 0.08, 0.05], "fov": 35}),
# SAMPLES (default 8), EDIT (a jq filter applied to the shot last, e.g. '.surfacing.debris_stretch = 1.2').
set -euo pipefail

ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${BUILD:-$ROOT/build}
THREADS=${THREADS:-2}
SAMPLES=${SAMPLES:-8}
EDIT=${EDIT:-.}
CAMERA=${CAMERA:-'{"position": [0.55, 0.45, 0.6], "target": [0.05, 0.08, 0.05], "fov": 35}'}
[[ $# -ge 4 ]] || { echo "usage: tools/closeup.sh SHOT OUT FRAME DEST_PREFIX [MODE...]" >&2; exit 2; }
SHOT=$1 OUT=$2 FRAME=$3 DEST=$4
shift 4
MODES=("$@")
[[ ${#MODES[@]} -gt 0 ]] || MODES=(ours plates)
[[ -f $SHOT ]] || { echo "closeup.sh: $SHOT: no such shot file" >&2; exit 1; }
[[ -f $OUT/sim/manifest.json ]] || { echo "closeup.sh: $OUT/sim/manifest.json: not found: simulate the shot first" >&2; exit 1; }
[[ $FRAME =~ ^[0-9]+$ ]] || { echo "closeup.sh: frame '$FRAME' is not a frame number" >&2; exit 1; }
for b in mc-shot mc-surface mc-render mc-measure; do
    [[ -x $BUILD/bin/$b ]] || { echo "closeup.sh: $BUILD/bin/$b is not built: run make build" >&2; exit 1; }
done
command -v jq >/dev/null || { echo "closeup.sh: jq not found (make deps installs it)" >&2; exit 1; }
echo "$CAMERA" | jq -e 'has("position") and has("target")' >/dev/null ||
    { echo "closeup.sh: CAMERA=$CAMERA: expected a JSON object with position and target" >&2; exit 1; }

WORK=$(mktemp -d "${TMPDIR:-/tmp}/closeup.XXXXXX")
trap 'rm -rf "$WORK"' EXIT
mkdir -p "$(dirname "$DEST")"
for mode in "${MODES[@]}"; do
    dir=$WORK/$mode
    mkdir -p "$dir"
    ln -s "$(cd "$OUT" && pwd)/init" "$dir/init"
    ln -s "$(cd "$OUT" && pwd)/sim" "$dir/sim"
    # the shot's canonical keys (mc-shot slice: defaults filled in), with the mode and the close-up's keys
    "$BUILD/bin/mc-shot" slice "$SHOT" render >"$dir/slice.json"
    jq --arg mode "$mode" --argjson camera "$CAMERA" --argjson samples "$SAMPLES" '
        .surfacing.mode = $mode | .render.resolution = [1600, 900] | .render.camera = $camera
        | .render.samples = $samples | del(.render.turntable) | del(.derived) | '"$EDIT" "$dir/slice.json" >"$dir/shot.json"
    "$BUILD/bin/mc-surface" --shot "$dir/shot.json" --out "$dir" --threads "$THREADS" --frames "$FRAME" --quiet \
        >"$dir/surface.log" 2>&1 || { echo "closeup.sh: mc-surface ($mode) failed:" >&2; tail -5 "$dir/surface.log" >&2; exit 1; }
    "$BUILD/bin/mc-render" --shot "$dir/shot.json" --out "$dir" --threads "$THREADS" --frames "$FRAME" --quiet \
        >"$dir/render.log" 2>&1 || { echo "closeup.sh: mc-render ($mode) failed:" >&2; tail -5 "$dir/render.log" >&2; exit 1; }
    cp "$dir/render/$(printf 'frame.%04d.png' "$FRAME")" "${DEST}_$mode.png"
    echo "== $mode: ${DEST}_$mode.png"
    "$BUILD/bin/mc-measure" --shot "$dir/shot.json" --out "$dir" --frames "$FRAME" | sed -n '/^surfacing meshes/,$p'
done
