#!/usr/bin/env bash
# The Blender add-on (tools/blender/mudcrack_blender) in real Blender, headless, on a
# shot's output (fig8_c's by default):
#
#   blender_playback_test.sh SOURCE_DIR BIN_DIR ADDON_ZIP [SHOT_FILE]   (SHOT_FILE default: fig8_c.json)
#
# SHOT_FILE must use the plates mode; the test runs a copy of it that adds
# "debris": "points" to /surfacing, so the output has pieces and debris files.
# 1. mc-init, mc-sim and mc-surface run the shot's frames 1-BLENDER_TEST_FRAMES (default 20: the
#    cracks of fig8_c open at frame 7) into a temporary folder, one thread each; all of its frames
#    when those have no frame without cracks and one with cracks before the last;
# 2. mc-surface writes the same frames as .obj too, from the shot as given (no debris), and in
#    the paper's surfacing, `ours`, whose fragment ids the add-on reads as piece ids like the
#    plates mode's: fig8_c's plates are one piece in every frame (README, Close-ups), its `ours`
#    fragments 10 by frame 20 (2026-11-27), so the piece checks see many ids;
#    blender_test_mesh_info (pipeline/io's assimp and debris readers, not the add-on's) reads
#    every mesh file, glb and obj, and every debris file of three frames: the first without a
#    crack file, the first with one, and the last;
# 3. cli.py, run as a plain script (blender --python), imports the shot and saves a .blend;
#    a bad folder makes it exit 1 naming the problem;
# 4. playback_check.py installs the add-on from ADDON_ZIP into a private Blender config, imports
#    the shot (glb, then obj, then ours) with the operator and checks the evaluated meshes at
#    those frames against step 2 (their "piece" attribute too), the debris points and their
#    attributes, the separated pieces, the empty crack mesh, materials, frame range, fps, y-up,
#    the cache, and the CLI's .blend;
# 5. a byte of the last frame's boundary file changed: cli.py refuses it, exit 1, naming the file
#    and "damaged".
# FAILS (does not skip) when blender is not installed: `make test` installs it.
# BLENDER_TEST_KEEP=1 keeps the temporary folder.
set -euo pipefail

fail() { echo "FAIL: $*" >&2; exit 1; }
[ $# -ge 3 ] || { echo "usage: blender_playback_test.sh SOURCE_DIR BIN_DIR ADDON_ZIP [SHOT_FILE]" >&2; exit 2; }
src=$(cd "$1" && pwd)
bin=$(cd "$2" && pwd)
zip=$3
given_shot=${4:-$src/shots/fig8_c.json}
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
frames=${BLENDER_TEST_FRAMES:-20}

command -v blender >/dev/null ||
    fail "blender not found: the add-on's test needs Debian's Blender (make test installs it: apt-get install blender)"
command -v jq >/dev/null || fail "jq not found (apt-get install jq)"
[ -f "$zip" ] || fail "$zip: not built (cmake --build BUILD --target mudcrack_blender_zip, or make blender-addon)"
for b in mc-init mc-sim mc-surface blender_test_mesh_info; do
    [ -x "$bin/$b" ] || fail "$bin/$b: not built"
done

tmp=$(mktemp -d "${TMPDIR:-/tmp}/mudcrack-blender.XXXXXX")
cleanup() {
    local rc=$?
    if [ "${BLENDER_TEST_KEEP:-0}" = 1 ] || [ $rc -ne 0 ]; then echo "blender_playback_test: kept $tmp"; else rm -rf "$tmp"; fi
}
trap cleanup EXIT
# the shot with debris points: a copy under the same name (the output folder is named after it)
grep -q '"mode": "plates"' "$given_shot" ||
    fail "$given_shot: the test covers the plates mode's pieces and debris: the shot must set \"mode\": \"plates\""
mkdir -p "$tmp/debris"
shot=$tmp/debris/$(basename "$given_shot")
sed 's/"surfacing": {/"surfacing": { "debris": "points",/' "$given_shot" >"$shot"
grep -q '"debris": "points"' "$shot" || fail "$given_shot: no '\"surfacing\": {' to add \"debris\": \"points\" to"
out=$tmp/$(basename "$shot" .json)
# a private Blender config: the add-on installs there, never in the user's ~/.config/blender
export BLENDER_USER_SCRIPTS=$tmp/blender-scripts BLENDER_USER_CONFIG=$tmp/blender-config
mkdir -p "$BLENDER_USER_SCRIPTS" "$BLENDER_USER_CONFIG"
blender_run() { blender -b --factory-startup --python-exit-code 1 "$@"; }

# run_stages [N]: mc-init, mc-sim and mc-surface over frames 1-N (all of the shot's without N)
run_stages() {
    rm -rf "$out"
    echo "== mc-init, mc-sim, mc-surface: frames ${1:+1-}${1:-all}"
    local stage flags
    for stage in init sim surface; do
        flags=(--shot "$shot" --out "$out" --threads 1 --quiet)
        [ "$stage" = init ] || [ -z "${1:-}" ] || flags+=(--frames "1-$1")
        "$bin/mc-$stage" "${flags[@]}" >"$tmp/$stage.txt" 2>&1 || { cat "$tmp/$stage.txt"; fail "mc-$stage failed"; }
    done
}
manifest=$out/surface/manifest.json
# the frames to look at: the first without a crack file, the first with one, the last
pick_frames() {
    no_crack=$(jq -r '[.per_frame[] | select(.crack.file == null) | .frame] | first // empty' "$manifest")
    with_crack=$(jq -r '[.per_frame[] | select(.crack.file != null) | .frame] | first // empty' "$manifest")
    last=$(jq -r '.frames.last' "$manifest")
    [ -n "$no_crack" ] && [ -n "$with_crack" ] && [ "$with_crack" != "$last" ]
}
run_stages "$frames"
if ! pick_frames; then
    # the shot's cracks open later than frame $frames now: the whole shot then
    echo "   frames 1-$frames lack a frame without and one with cracks before the last: all frames"
    run_stages
    pick_frames || fail "$manifest: the test needs a frame without a crack file and one with cracks before the last" \
        "(no_crack='$no_crack' with_crack='$with_crack' last=$last)"
fi
jq -e '.frames.fps > 0' "$manifest" >/dev/null || fail "$manifest: no /frames/fps"
echo "   frames: $no_crack (no crack file), $with_crack (first cracks), $last (last)"

# surface_variant NAME FROM TO: the same frames surfaced again (init/ and sim/ shared) from the
# shot as given with FROM replaced by TO, into $tmp/NAME/<shot>
first=$(jq -r .frames.first "$manifest")
surface_variant() {
    local dir=$tmp/$1/$(basename "$out")
    mkdir -p "$dir"
    ln -s "$out/init" "$dir/init"
    ln -s "$out/sim" "$dir/sim"
    sed "s/$2/$3/" "$given_shot" >"$tmp/$1/shot.json"
    grep -q "$3" "$tmp/$1/shot.json" || fail "$given_shot: no '$2' to turn into '$3'"
    "$bin/mc-surface" --shot "$tmp/$1/shot.json" --out "$dir" --frames "$first-$last" --threads 1 --quiet \
        >"$tmp/surface_$1.txt" 2>&1 || { cat "$tmp/surface_$1.txt"; fail "mc-surface ($3) failed"; }
}
# as .obj, for the add-on's obj reader; in `ours`, for many piece ids
surface_variant obj '"format": "glb"' '"format": "obj"'
surface_variant ours '"mode": "plates"' '"mode": "ours"'
obj_out=$tmp/obj/$(basename "$out")
ours_out=$tmp/ours/$(basename "$out")

# expected counts, read with the pipeline's own reader
files=()
for f in "$no_crack" "$with_crack" "$last"; do
    for dir in "$out" "$obj_out" "$ours_out"; do
        while IFS= read -r name; do files+=("$dir/surface/$name"); done < <(
            jq -r --argjson f "$f" '.per_frame[] | select(.frame == $f) | .boundary.file, (.crack.file // empty),
                (.debris.file // empty)' "$dir/surface/manifest.json")
    done
done
"$bin/blender_test_mesh_info" "${files[@]}" >"$tmp/expected.json" || fail "blender_test_mesh_info failed"
jq -e 'to_entries | map(select(.value.points == null)) | all(.value.vertices > 0 and .value.faces > 0 and .value.uvs and .value.colors)' \
    "$tmp/expected.json" >/dev/null || fail "$tmp/expected.json: a mesh file without faces, UVs or colors"
jq -e 'to_entries | map(select(.key | endswith(".glb"))) | all(.value.pieces > 0)' "$tmp/expected.json" >/dev/null ||
    fail "$tmp/expected.json: a glb file without piece ids"
jq -e --arg f "$ours_out/surface/$(printf 'crack.%04d.glb' "$last")" '.[$f].pieces > 1' "$tmp/expected.json" >/dev/null ||
    fail "$tmp/expected.json: the ours variant's last crack file has no more than one piece id"
# debris files for every frame, and points in the last, or the test would not cover them
jq -e --argjson last "$last" '(.per_frame | all(.debris.file != null)) and
    (.per_frame[] | select(.frame == $last) | .debris.points > 0)' "$manifest" >/dev/null ||
    fail "$manifest: expected a debris file for every frame and debris points at frame $last"
echo "   debris points at frame $last: $(jq --argjson last "$last" '.per_frame[] | select(.frame == $last) | .debris.points' "$manifest")"

echo "== cli.py as a plain script"
cli=$src/tools/blender/mudcrack_blender/cli.py
blender_run --python "$cli" -- "$out" --frame last --save "$tmp/cli.blend" >"$tmp/cli.txt" 2>&1 ||
    { cat "$tmp/cli.txt"; fail "cli.py failed on $out"; }
grep -q "^mudcrack_blender: $(basename "$out"): frames $(jq -r .frames.first "$manifest")-$last at " "$tmp/cli.txt" || { cat "$tmp/cli.txt"; fail "cli.py did not report the shot"; }
[ -f "$tmp/cli.blend" ] || fail "cli.py --save wrote no $tmp/cli.blend"
mkdir -p "$tmp/not_a_shot"
set +e
blender_run --python "$cli" -- "$tmp/not_a_shot" >"$tmp/cli_bad.txt" 2>&1
rc=$?
set -e
[ $rc -eq 1 ] || { cat "$tmp/cli_bad.txt"; fail "cli.py on a folder without a manifest exited $rc, expected 1"; }
grep -q "^mudcrack_blender: error: $tmp/not_a_shot: .*manifest.json" "$tmp/cli_bad.txt" ||
    { cat "$tmp/cli_bad.txt"; fail "cli.py on a folder without a manifest: no clear error"; }

echo "== the add-on, installed from $zip"
blender_run --python "$here/playback_check.py" -- --zip "$zip" --shot "$out" --expected "$tmp/expected.json" \
    --frames "$no_crack,$with_crack,$last" --blend "$tmp/cli.blend" --obj-shot "$obj_out" --ours-shot "$ours_out" \
    >"$tmp/check.txt" 2>&1 ||
    { cat "$tmp/check.txt"; fail "playback_check.py failed"; }
grep "^playback_check:" "$tmp/check.txt"
grep -q "^playback_check: all checks passed" "$tmp/check.txt" || { cat "$tmp/check.txt"; fail "playback_check.py did not finish"; }

echo "== a damaged mesh file: refused, naming it"
damaged=$out/surface/$(jq -r --argjson f "$last" '.per_frame[] | select(.frame == $f) | .boundary.file' "$manifest")
offset=$(($(stat -c %s "$damaged") / 2))
byte=$(dd if="$damaged" bs=1 skip=$offset count=1 status=none | od -An -tu1)
printf "\\x$(printf %02x $((255 - byte)))" | dd of="$damaged" bs=1 seek=$offset conv=notrunc status=none
set +e
blender_run --python "$cli" -- "$out" --frame last >"$tmp/cli_damaged.txt" 2>&1
rc=$?
set -e
[ $rc -eq 1 ] || { cat "$tmp/cli_damaged.txt"; fail "cli.py on a damaged $damaged exited $rc, expected 1"; }
grep -q "^mudcrack_blender: error: $damaged: damaged" "$tmp/cli_damaged.txt" ||
    { cat "$tmp/cli_damaged.txt"; fail "cli.py on a damaged mesh file: no message naming it and \"damaged\""; }
echo "PASS"
