#!/usr/bin/env bash
# The README's Blender still: a shot's last frame imported with the Blender add-on
# (tools/blender/mudcrack_blender) and rendered by Blender itself (Cycles on the CPU, headless),
# next to mc-render's preview of the same frame, both 640x360 PNGs in docs/blender/:
#   docs/blender/<shot>_blender.png      Blender (cli.py --render), mc-render's camera
#   docs/blender/<shot>_mc_render.png    mc-render's render/frame.<last>.png
#
#   tools/blender_still.sh [OUT_DIR [SHOT [SAMPLES]]]     defaults: out demo 32
#   make blender-still [SHOT=demo]                        the shot's stages first, then this
#
# The shot's stages must have run (make shot SHOT=<shot>); the render's resolution is the
# shot's (/render/resolution, demo: 640x360). Needs blender (make test-deps installs it).
set -euo pipefail
out=${1:-out}
shot=${2:-demo}
samples=${3:-32}
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
dir=$out/$shot
dest=$root/docs/blender
command -v blender >/dev/null || { echo "blender_still: blender not found (make test-deps installs it)" >&2; exit 1; }
command -v jq >/dev/null || { echo "blender_still: jq not found" >&2; exit 1; }
for m in surface render; do
    [ -f "$dir/$m/manifest.json" ] || { echo "blender_still: $dir/$m/manifest.json: missing: run make shot SHOT=$shot" >&2; exit 1; }
done
last=$(jq -r .frames.last "$dir/surface/manifest.json")
read -r width height < <(jq -r '.resolution | "\(.[0]) \(.[1])"' "$dir/render/manifest.json")
preview=$(printf '%s/render/frame.%04d.png' "$dir" "$last")
[ -f "$preview" ] || { echo "blender_still: $preview: missing (mc-render did not render frame $last)" >&2; exit 1; }
mkdir -p "$dest"

start=$(date +%s.%N)
blender -b --factory-startup --python-exit-code 1 --python "$root/tools/blender/mudcrack_blender/cli.py" -- \
    "$dir" --frame last --render "$dest/.${shot}_blender.tmp.png" --resolution "$width" "$height" \
    --samples "$samples" >"$dest/.${shot}_blender.log" 2>&1 ||
    { cat "$dest/.${shot}_blender.log" >&2; rm -f "$dest/.${shot}_blender.tmp.png"; exit 1; }
seconds=$(awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN { print b - a }')
grep '^mudcrack_blender:' "$dest/.${shot}_blender.log"
rm -f "$dest/.${shot}_blender.log"
mv -f "$dest/.${shot}_blender.tmp.png" "$dest/${shot}_blender.png"
cp -f "$preview" "$dest/${shot}_mc_render.png"
printf 'blender_still: %s frame %d, %dx%d, %d samples: Blender (import + Cycles) %.1f s\n' \
    "$shot" "$last" "$width" "$height" "$samples" "$seconds"
echo "$dest/${shot}_blender.png"
echo "$dest/${shot}_mc_render.png <- $preview"
