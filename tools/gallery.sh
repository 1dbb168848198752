#!/usr/bin/env bash
# The gallery: for each shot, a 640x360 still and its contact sheet copied from the shot's render,
# next to one sentence of what the paper's figure shows, the `mc-measure` numbers that show ours
# does the same, and each stage's wall time and peak memory read from its manifest. Each shot
# becomes docs/gallery/<shot>.md (with <shot>.png and <shot>_contact.jpg); the block between the
# "gallery begin/end" markers of docs/gallery.md is then rebuilt from every fragment there, and the
# README's block between the same markers becomes a grid of the stills linking to it, both in the
# order of kShotOrder below, so one shot can be redone without the others.
#
#   tools/gallery.sh OUT SHOT[@FRAME]...     e.g. tools/gallery.sh out demo fig4_bunny@32
#
# The still is view 1 of the turntable around the last frame, or frame FRAME of the shot's camera
# when one is named (the frame that shows the effect best). The shot must have been run to the end
# with every stage (`make shot SHOT=<shot>`; `make gallery` does both). mc-measure runs once per
# shot and its table is kept as OUT/<shot>/measure.json until a stage runs again.
# Environment: BUILD (default build), THREADS (mc-measure's, default 2).
set -euo pipefail

ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${BUILD:-$ROOT/build}
THREADS=${THREADS:-2}
DEST=$ROOT/docs/gallery
README=$ROOT/README.md
GALLERY=$ROOT/docs/gallery.md
kShotOrder=(demo demo_float fig4_bunny fig5_riverbed fig6_eps_0.2 fig6_eps_0.5 fig6_eps_1.0
            fig7_mossy_ground fig7_mossy_ground_float fig8_a fig8_b fig8_c fig9 fig10_ours
            fig10_wang2019)

die() { echo "gallery.sh: $*" >&2; exit 1; }
[[ $# -ge 2 ]] || { echo "usage: tools/gallery.sh OUT SHOT[@FRAME]..." >&2; exit 2; }
OUT=$1
shift
for tool in jq ffmpeg; do command -v $tool >/dev/null || die "$tool not found (make deps installs it)"; done
for tool in mc-measure mc-shot; do
    [[ -x $BUILD/bin/$tool ]] || die "$BUILD/bin/$tool is not built: run make build"
done
for page in "$README" "$GALLERY"; do
    grep -q '^<!-- gallery begin -->$' "$page" && grep -q '^<!-- gallery end -->$' "$page" ||
        die "$page has no <!-- gallery begin --> / <!-- gallery end --> lines to fill"
done

# What the paper's figure shows, one sentence per shot (Tu et al. 2023; the demo is ours).
paper_says() {
    case $1 in
        demo) echo "(ours, what \`make demo\` runs) a round puddle of wet mud that dries through and cracks into a closed network of polygonal plates, the cracks coming across the shot." ;;
        demo_float) echo "(ours) the demo with its particle state kept in float (/sim/precision): to hold against the demo's still." ;;
        fig4_bunny) echo "Fig. 4: a bunny made with wet soil gradually breaks into a pile of pieces." ;;
        fig5_riverbed) echo "Fig. 5: a riverbed dried in the sun shows deep cracks." ;;
        fig6_eps_*) echo "Fig. 6 (eps = ${1#fig6_eps_}): the larger the hardening rate eps, the more the soil curls and the larger its fragments." ;;
        fig7_mossy_ground) echo "Fig. 7: a mossy ground shrinks, cracks into polygons and curls." ;;
        fig7_mossy_ground_float) echo "Fig. 7 with its particle state kept in float (/sim/precision): to hold against fig7_mossy_ground's still." ;;
        fig8_a) echo "Fig. 8(a), eta = 0: without porous shrinkage the soil neither shrinks nor cracks." ;;
        fig8_b) echo "Fig. 8(b), eps = 0: NACC alone cracks vertically only, without curling." ;;
        fig8_c) echo "Fig. 8(c), the full model: the crust curls up through horizontal fractures." ;;
        fig9) echo "Fig. 9: the hardening states; stretched (red) and compressed (blue) regions of Fig. 8(c)." ;;
        fig10_ours) echo "Fig. 10, ours: the moisture-aware surfacing shows more cracks, in the dry areas." ;;
        fig10_wang2019) echo "Fig. 10, Wang et al. 2019: the baseline criterion on the same simulation shows fewer." ;;
        *) return 1 ;;
    esac
}

# The newest created_utc among a shot's stage manifests, and whether measure.json is older.
measure_is_stale() {
    local dir=$1 m
    [[ -f $dir/measure.json ]] || return 0
    for m in "$dir"/{init,sim,surface}/manifest.json; do
        [[ -f $m && $m -nt $dir/measure.json ]] && return 0
    done
    return 1
}

# The stages' costs, "init 0.3 s, 84 MiB; sim 111 s, 118 MiB; ...", from `mc-shot summary --json`
# (the stages' manifests); a stage taken from another shot (/reuse) names that shot, which ran it,
# and a sim resumed from a checkpoint says so (its time covers only the frames after it).
stage_costs() {
    local dir=$1 shot=$2
    "$BUILD/bin/mc-shot" summary --json "$dir" | jq -r --arg shot "$shot" '[.stages[]
        | "\(.stage) \(.wall_seconds * 10 | round / 10) s, \(.peak_memory_bytes / 1048576 | round) MiB"
          + (if .resumed_from_frame then " (resumed from frame \(.resumed_from_frame): the frames after it only)" else "" end)
          + ((.shot // $shot) | split("/") | last | rtrimstr(".json") | if . == $shot then "" else " (\(.)'"'"'s, reused)" end)]
        | join("; ")'
}

mkdir -p "$DEST"
for arg in "$@"; do
    shot=${arg%@*}
    frame=""
    [[ $arg == *@* ]] && frame=${arg#*@}
    [[ -z $frame || $frame =~ ^[0-9]+$ ]] || die "$arg: the frame after @ must be a frame number"
    sentence=$(paper_says "$shot") || die "$shot: not a figure shot (known: ${kShotOrder[*]})"
    shotfile=$ROOT/shots/$shot.json
    dir=$OUT/$shot
    [[ -f $shotfile ]] || die "$shotfile: no such shot"
    [[ -f $dir/render/manifest.json ]] ||
        die "$dir/render/manifest.json: the shot has not been rendered to the end: run make shot SHOT=$shot"
    read -r width height < <(jq -r '.resolution | "\(.[0]) \(.[1])"' "$dir/render/manifest.json")
    # 640x360, or a larger 16:9 render (the riverbed renders 960x540 for its terrain) scaled down
    ((width >= 640 && width * 9 == height * 16)) ||
        die "$dir/render: rendered at ${width}x$height, the gallery wants 640x360 or a larger 16:9 size (/render/resolution)"

    if [[ -n $frame ]]; then
        still=$(printf '%s/render/frame.%04d.png' "$dir" "$frame")
        label="frame $frame"
    else
        still=$dir/render/turntable.0001.png
        label="the last frame, turntable view 1"
    fi
    [[ -f $still ]] || die "$still: no such render (name a rendered frame, or give the shot a turntable)"
    if ((width == 640)); then
        cp "$still" "$DEST/.$shot.png.tmp"
    else
        ffmpeg -loglevel error -y -i "$still" -vf scale=640:360:flags=lanczos -f image2 -c:v png "$DEST/.$shot.png.tmp"
    fi
    mv -f "$DEST/.$shot.png.tmp" "$DEST/$shot.png"
    ffmpeg -loglevel error -y -i "$dir/render/contact_sheet.png" -vf scale=1280:-2 -q:v 4 "$DEST/.${shot}_contact.tmp.jpg"
    mv -f "$DEST/.${shot}_contact.tmp.jpg" "$DEST/${shot}_contact.jpg"

    if measure_is_stale "$dir"; then
        "$BUILD/bin/mc-measure" --shot "$shotfile" --out "$dir" --threads "$THREADS" --quiet \
            --json "$dir/.measure.json.tmp" >/dev/null || die "mc-measure failed on $dir"
        mv -f "$dir/.measure.json.tmp" "$dir/measure.json"
    fi
    measure_frame=${frame:-$(jq '.frames[-1].frame' "$dir/measure.json")}
    # the numbers of the still's frame, only those that say something on this shot
    numbers=$(jq -r --argjson f "$measure_frame" '
        def pct: . * 1000 | round / 10 | tostring + " %";
        def mm: . * 10000 | round / 10 | tostring + " mm";
        def commas: if length > 3 then (.[:-3] | commas) + "," + .[-3:] else . end;
        def int: tostring | commas;
        (.frames | map(select(.frame == $f)) | first) as $m
        | if $m == null then error("frame \($f) was not measured") else . end
        | [ "frame \($m.frame) (\($m.time * 100 | round / 100) s)",
            "top \($m.top_rise_median | mm)",
            "curl \($m.curl | mm)",
            "\($m.broken_edges | int) broken edges",
            (if $m.surface_polygons > 1 then "\($m.surface_polygons) crack polygons (\($m.effective_surface_polygons * 100 | round / 100) effective plates, the largest \($m.largest_polygon_fraction | pct))" else empty end),
            (if $m.fragments > 1 then "\($m.fragments) fragments (the largest \($m.largest_fragment_fraction | pct) of the soil)" else empty end),
            "\($m.split_fraction | pct) of columns split" + (if $m.split_fraction > 0 then " \($m.split_height_median_cells * 10 | round / 10) cells up" else "" end),
            "\($m.lifted_fraction | pct) lifted",
            (if $m.oriented_crack_points > 0 then "\($m.axis_aligned_fraction | pct) of the crack length along the grid axes" + (if $m.axis_aligned_fraction_stderr != null then " (standard error \($m.axis_aligned_fraction_stderr | pct) over its \($m.oriented_cracks) cracks)" else "" end) else empty end),
            (if $m.junctions > 0 then "\($m.junctions) junctions (\($m.t_junction_fraction | pct) T, \($m.y_junction_fraction | pct) Y)" else empty end),
            (if ($m.cracked_top_fraction // 0) > 0 then "\($m.cracked_top_fraction | pct) of the top cracked, \($m.crack_depth_p90 * 100 | round / 100) m deep at the 90th percentile (\($m.crack_depth_max * 100 | round / 100) m at most)" else empty end),
            "surface \($m.surface_stretched_fraction | pct) stretched, \($m.surface_compressed_fraction | pct) compressed",
            (if $m.mesh_surface_polygons != null then "as the plates meshes cut the top: \($m.mesh_pieces) piece\(if $m.mesh_pieces == 1 then "" else "s" end), \($m.mesh_surface_polygons) polygons (\($m.mesh_effective_surface_polygons * 100 | round / 100) effective plates, the largest \($m.mesh_largest_polygon_fraction | pct))" + (if $m.mesh_oriented_crack_points > 0 then ", \($m.mesh_axis_aligned_fraction | pct) of the wall line along the grid axes" else "" end) else empty end)
          ] | join("; ")' "$dir/measure.json") || die "$dir/measure.json: cannot read frame $measure_frame"
    # how the pieces grew: the fragment count at five frames across the shot
    growth=$(jq -r '.frames as $fs | ($fs | length) as $n
        | if ($fs | map(.fragments) | max) > 1 and $n >= 5
          then [range(0; 5) | $fs[(. * ($n - 1) / 4 | floor)] | "\(.fragments) (frame \(.frame))"] | "fragments over time: " + join(", ")
          else empty end' "$dir/measure.json")
    costs=$(stage_costs "$dir" "$shot") || die "$dir: mc-shot summary cannot read its stages' manifests"
    read -r threads date < <(jq -r '"\(.threads) \(.created_utc[:10])"' "$dir/render/manifest.json")

    {
        echo "### \`$shot\`"
        echo
        echo "![$shot](gallery/$shot.png)"
        echo
        echo "- The paper: $sentence"
        echo "- Ours, $label (\`mc-measure\`): $numbers.${growth:+ $growth.}"
        echo "- [Contact sheet](gallery/${shot}_contact.jpg) of every frame. Stages (\`mc-shot summary $OUT/$shot\`, $threads threads, $date): $costs."
        echo
    } >"$DEST/.$shot.md.tmp"
    mv -f "$DEST/.$shot.md.tmp" "$DEST/$shot.md"
    echo "$DEST/$shot.md"
done

# Rebuild docs/gallery.md's block from every fragment, in figure order, and the README's grid of
# stills, three to a row, each linking to its shot's entry there.
block=$(mktemp) grid=$(mktemp)
trap 'rm -f "$block" "$grid"' EXIT
missing=() shown=()
for shot in "${kShotOrder[@]}"; do
    if [[ -f $DEST/$shot.md ]]; then cat "$DEST/$shot.md" >>"$block"; shown+=("$shot"); else missing+=("$shot"); fi
done
[[ ${#missing[@]} -eq 0 ]] || printf 'Not in the gallery yet: %s.\n\n' "${missing[*]}" >>"$block"
{
    echo "| | | |"
    echo "| --- | --- | --- |"
    for ((i = 0; i < ${#shown[@]}; i += 3)); do
        row="|"
        for shot in "${shown[@]:i:3}"; do
            row+=" [![$shot](docs/gallery/$shot.png)](docs/gallery.md#${shot//./}) \`$shot\` |"
        done
        echo "$row"
    done
    echo
} >"$grid"
fill() {  # fill PAGE's block between the markers with FILE
    awk -v blockfile="$2" '
        /^<!-- gallery begin -->$/ { print; while ((getline line < blockfile) > 0) print line; skipping = 1; next }
        /^<!-- gallery end -->$/ { skipping = 0 }
        !skipping' "$1" >"$1.tmp"
    mv -f "$1.tmp" "$1"
}
fill "$GALLERY" "$block"
fill "$README" "$grid"
echo "$GALLERY: gallery of ${#shown[@]} shots; $README: their stills"
