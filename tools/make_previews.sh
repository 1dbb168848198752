#!/usr/bin/env bash
# Makes the README's shot previews: a turntable still of each shot (the first view of the
# turntable around its last frame), or its last rendered frame when it has no turntable (a run of
# some frames only), scaled to 320 px wide, as shots/previews/<shot>.png (ffmpeg, which `make deps`
# installs for the movies).
#
#   tools/make_previews.sh OUT_DIR SHOT...     e.g. tools/make_previews.sh out fig8_b fig8_c
set -euo pipefail
[ $# -ge 2 ] || { echo "usage: tools/make_previews.sh OUT_DIR SHOT..." >&2; exit 2; }
out=$1; shift
dest=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)/shots/previews
mkdir -p "$dest"
for shot in "$@"; do
    frame=$out/$shot/render/turntable.0001.png
    [ -f "$frame" ] || frame=$(ls "$out/$shot/render"/frame.*.png 2>/dev/null | sort | tail -n 1)
    [ -n "$frame" ] || { echo "make_previews: $out/$shot/render has no frame.*.png: render $shot first" >&2; exit 1; }
    ffmpeg -loglevel error -y -i "$frame" -vf scale=320:-2 "$dest/.$shot.png.tmp.png"
    mv -f "$dest/.$shot.png.tmp.png" "$dest/$shot.png"
    echo "$dest/$shot.png <- $frame"
done
