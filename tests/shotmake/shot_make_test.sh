#!/usr/bin/env bash
# The shot Makefile's claims on a shot (ctest passes Fig. 8(c)'s slab), through the make rules
# themselves (pipeline/shot.mk, run the way the root Makefile's `shot` target runs them, without
# its build and deps steps):
#
#   shot_make_test.sh SOURCE_DIR BIN_DIR [SHOT_FILE]     (SHOT_FILE default: SOURCE_DIR/shots/fig8_c.json)
#
# 1. a serial `make shot-run shot-summary` into TMP/serial runs every stage over all frames and
#    prints the summary table;
# 2. `make -j2` into TMP/parallel (its init and sim copied from the serial run, timestamps kept, so
#    make must see them as done) runs only surfacing and rendering, as frame chunks, two render
#    chunks at the same time, and writes exactly the serial run's files, byte for byte;
# 3. a second run (serial and -j2) does nothing;
# 4. editing only a render key re-runs only the render (serial and -j2), still byte-identical;
# 5. a render chunk that fails (a truncated surface mesh) fails make, naming the chunk's frames and
#    its log; once the mesh is back, the next run renders again and matches the serial run.
# The shot is a copy in TMP (SHOT_FILE=...), so the test edits it without touching shots/; the
# copy renders the shot's first 24 frames at 320x180 (not 640x360), with 6 turntable views.
# FAILS rather than skips when jq (a dependency of the make pipeline) is missing.
# SHOT_MAKE_TEST_KEEP=1 keeps the temporary folder.
set -euo pipefail

# shellcheck source=make_test_lib.sh
. "$(dirname "${BASH_SOURCE[0]}")/make_test_lib.sh"
make_test_setup shot_make_test fig8_c "$@"
name=$(basename "$shot_src" .json)
shot=$tmp/$name.json
# a quarter of the pixels (a render key: the stages before it are the shot's own) keeps the four
# render runs short; so does the cut every long pipeline test runs (tests/short_shot.sh: the first
# 24 frames, a 6-view turntable, a quarter of the slab's footprint; an earlier demo's 28,611
# particles over 48 frames took 846 s of the test's 900 on a loaded 2-core machine)
# shellcheck source=../short_shot.sh
. "$src/tests/short_shot.sh"
sed 's/"resolution": \[640, 360\]/"resolution": [320, 180]/' "$shot_src" >"$tmp/reduced.json"
short_shot "$tmp/reduced.json" >"$shot" || fail "$shot_src: cannot shorten it with jq"
[ "$(jq -c .render.resolution "$shot")" = "[320,180]" ] || fail "$shot_src: no '\"resolution\": [640, 360]' to reduce"
serial=$tmp/serial/$name
parallel=$tmp/parallel/$name

# make_goals OUT_ROOT GOALS [MAKE_ARGS...]: pipeline/shot.mk as the root Makefile runs it, for
# this shot; output in $tmp/make.txt
make_goals() {
    local root=$1 goals=$2
    shift 2
    # shellcheck disable=SC2086
    make --no-print-directory -C "$src" -f Makefile -f pipeline/shot.mk $goals \
        SHOT="$name" SHOT_FILE="$shot" OUT="$root" BUILD="$(dirname "$bin")" BIN="$bin" "$@" >"$tmp/make.txt" 2>&1
}
# shot_make OUT_ROOT [MAKE_ARGS...]: the root Makefile's `shot` recipe
shot_make() { local root=$1; shift; make_goals "$root" "shot-run shot-summary" "$@"; }
# the stage binaries and chunk tasks a make run started, one per line
ran() { grep -E -o '(/mc-(init|sim|surface|render) |mudcrack: [^:]+: [a-z-]+( frames [0-9-]+)?)' "$tmp/make.txt" |
        sed -E 's|^/||; s|^mudcrack: [^:]+: ||; s| $||' | tr '\n' ',' || true; }
mtimes() { stat -c '%n %Y.%y' "$1"/{init,sim,surface,render}/manifest.json; }
frames() { jq -r '"\(.frames.start) \(.frames.end)"' "$serial/sim.params.json"; }

# every mesh, image, movie, cache and break history of the serial run is in the parallel run, byte
# for byte, and the parallel run has no other such file
compare_runs() {
    local compared=0 file rel
    while IFS= read -r -d '' file; do
        rel=${file#"$serial"/}
        [ -f "$parallel/$rel" ] || fail "make -j2 did not write $rel"
        cmp -s "$file" "$parallel/$rel" || fail "$rel differs between the serial and the make -j2 run"
        compared=$((compared + 1))
    done < <(find "$serial"/{init,sim,surface,render} -type f \( -name '*.vdb' -o -name '*.vtu' -o -name '*.glb' \
        -o -name '*.png' -o -name '*.mp4' -o -name 'edge_breaks.bin' \) -print0)
    while IFS= read -r -d '' file; do
        rel=${file#"$parallel"/}
        [ -f "$serial/$rel" ] || fail "make -j2 wrote $rel, the serial run did not"
    done < <(find "$parallel"/{init,sim,surface,render} -type f \( -name '*.vdb' -o -name '*.vtu' -o -name '*.glb' \
        -o -name '*.png' -o -name '*.mp4' -o -name 'edge_breaks.bin' \) -print0)
    local entries='[.per_frame[] | [.frame, .boundary.faces, .broken_edges, .fragments, .boundary.crc32, .crack.crc32]]'
    [ "$(jq -c "$entries" "$serial/surface/manifest.json")" = "$(jq -c "$entries" "$parallel/surface/manifest.json")" ] ||
        fail "surface/manifest.json per_frame entries differ between the serial and the make -j2 run"
    # the checksums readers verify: the chunked run records the serial run's
    [ "$(jq -c .images "$serial/render/manifest.json")" = "$(jq -c .images "$parallel/render/manifest.json")" ] ||
        fail "render/manifest.json /images differ between the serial and the make -j2 run"
    for stage in surface render; do
        [ "$(jq -cS .frames "$serial/$stage/manifest.json")" = "$(jq -cS .frames "$parallel/$stage/manifest.json")" ] ||
            fail "$stage/manifest.json frames differ: $(jq -cS .frames "$serial/$stage/manifest.json") vs $(jq -cS .frames "$parallel/$stage/manifest.json")"
    done
    echo "   $compared files byte-identical"
}

echo "== serial make of $name"
# init and sim first, one thread (a two-thread sim on a loaded 2-core machine mostly waits at its
# barriers: measured 193 s against 18 s); the shot-run after them must see them done
make_goals "$tmp/serial" "$tmp/serial/$name/sim/manifest.json" THREADS=1 || { cat "$tmp/make.txt"; fail "the serial make of the sim failed"; }
[ "$(ran)" = "mc-init,mc-sim," ] || { cat "$tmp/make.txt"; fail "making the sim manifest ran '$(ran)', expected mc-init and mc-sim"; }
shot_make "$tmp/serial" || { cat "$tmp/make.txt"; fail "the serial make failed"; }
[ "$(ran)" = "mc-surface,mc-render," ] || { cat "$tmp/make.txt"; fail "the serial make ran '$(ran)', expected mc-surface and mc-render once each"; }
# the summary table, last: a row per stage
tail -n 4 "$tmp/make.txt" | cut -c1-8 | tr -s ' \n' ' ' | grep -qx 'init sim surface render ' ||
    { cat "$tmp/make.txt"; fail "make does not end with the summary table (a row per stage)"; }
read -r first last < <(frames)
echo "   frames $first-$last"

echo "== make -j2 (init and sim copied from the serial run)"
mkdir -p "$parallel"
cp -a "$serial"/{init,sim,init.params.json,sim.params.json} "$parallel/"
shot_make "$tmp/parallel" -j2 || { cat "$tmp/make.txt"; fail "make -j2 failed"; }
cat "$tmp/make.txt" | grep '^mudcrack:' | sed 's/^/   /'
# -j2: the surfacing in 3 chunks (the first alone), the render in 2, as pipeline/shot.mk documents
count=$((last - first + 1))
s=$(((count + 2) / 3)) r=$(((count + 1) / 2))
expected="surface-prep frames $first-$((first + s - 1)),"
got=$(ran)
for part in "$expected" "surface-chunk frames $((first + s))-$((first + 2 * s - 1))," "surface-chunk frames $((first + 2 * s))-$last," \
            "surface-merge," "render-chunk frames $first-$((first + r - 1))," "render-chunk frames $((first + r))-$last," "render-assemble,"; do
    [[ $got == *"$part"* ]] || { cat "$tmp/make.txt"; fail "make -j2 ran '$got': no '$part'"; }
done
[[ $got != *mc-init* && $got != *mc-sim* ]] || fail "make -j2 re-ran init or sim although they were done: $got"
[[ $got == "$expected"* ]] || fail "make -j2 did not start with the first surfacing chunk: $got"
[[ $got == *"render-assemble," ]] || fail "make -j2 did not end with the render assembly: $got"
tail -n 4 "$tmp/make.txt" | cut -c1-8 | tr -s ' \n' ' ' | grep -qx 'init sim surface render ' ||
    { cat "$tmp/make.txt"; fail "make -j2 does not end with the summary table (it must wait for the stages)"; }
# the two render chunks ran at the same time (each started before the other ended)
st() { sed -n "s/^$2=//p" "$parallel/farm/state/$1"; }
r1=$(printf 'render.%04d-%04d' "$first" $((first + r - 1))) r2=$(printf 'render.%04d-%04d' $((first + r)) "$last")
awk -v s1="$(st "$r1" start)" -v e1="$(st "$r1" end)" -v s2="$(st "$r2" start)" -v e2="$(st "$r2" end)" \
    'BEGIN { exit !(s1 < e2 && s2 < e1) }' || fail "the render chunks $r1 and $r2 did not overlap in time"
compare_runs

echo "== a second run does nothing"
for root in serial parallel; do
    before=$(mtimes "$tmp/$root/$name")
    shot_make "$tmp/$root" -j2 || { cat "$tmp/make.txt"; fail "the second make ($root) failed"; }
    [ -z "$(ran)" ] || fail "the second make ($root) ran: $(ran)"
    [ "$(mtimes "$tmp/$root/$name")" = "$before" ] || fail "the second make ($root) rewrote a manifest"
done

echo "== editing only a render key re-runs only the render"
jq '.render.turntable.views = 3' "$shot" >"$shot.edited" && mv "$shot.edited" "$shot"
for root in serial parallel; do
    before=$(mtimes "$tmp/$root/$name" | head -n 3)
    if [ $root = serial ]; then jobs=-j1; else jobs=-j2; fi
    shot_make "$tmp/$root" $jobs || { cat "$tmp/make.txt"; fail "the render-only make ($root) failed"; }
    [ "$(mtimes "$tmp/$root/$name" | head -n 3)" = "$before" ] || fail "the render-only edit rewrote an init, sim or surface manifest ($root)"
    if [ $root = serial ]; then
        [ "$(ran)" = "mc-render," ] || fail "the render-only edit ran '$(ran)' (serial), expected mc-render only"
    else
        [ "$(ran)" = "render-chunk frames $first-$((first + r - 1)),render-chunk frames $((first + r))-$last,render-assemble," ] ||
            [ "$(ran)" = "render-chunk frames $((first + r))-$last,render-chunk frames $first-$((first + r - 1)),render-assemble," ] ||
            fail "the render-only edit ran '$(ran)' (make -j2), expected the two render chunks and the assembly"
    fi
    [ "$(jq .views "$tmp/$root/$name/render/manifest.json")" = 3 ] || fail "render/manifest.json ($root) does not have the 3 views of the edit"
done
compare_runs

# every render chunk reads every frame's mesh (the camera frames the bounds of all of them), so
# each chunk fails; the last chunk's message is checked
echo "== a failed render chunk fails make"
mesh=$(printf '%s/surface/boundary.%04d.glb' "$parallel" "$last")
[ -f "$mesh" ] || fail "no $mesh"
cp -p "$mesh" "$tmp/mesh.keep"
: >"$mesh"
rm "$parallel/render/manifest.json"
if shot_make "$tmp/parallel" -j2; then cat "$tmp/make.txt"; fail "make -j2 succeeded with an empty $mesh"; fi
failed_task=$(printf 'render.%04d-%04d' $((first + r)) "$last")
grep -q "$failed_task (frames $((first + r))-$last) FAILED (exit [0-9]*); log $parallel/logs/$failed_task.log" "$tmp/make.txt" ||
    { cat "$tmp/make.txt"; fail "make's output does not name the failed chunk $failed_task, its frames and its log"; }
grep -q "boundary.$(printf %04d "$last").glb" "$tmp/make.txt" || { cat "$tmp/make.txt"; fail "make's output does not show the chunk's error (the empty mesh)"; }
[ ! -f "$parallel/render/manifest.json" ] || fail "a failed render chunk left a render manifest"
sed -n '/FAILED/,$p' "$tmp/make.txt" | head -n 4 | sed 's/^/   /'
cp -p "$tmp/mesh.keep" "$mesh"
shot_make "$tmp/parallel" -j2 || { cat "$tmp/make.txt"; fail "make -j2 after restoring the mesh failed"; }
[[ "$(ran)" == render-chunk*render-chunk*render-assemble, ]] || fail "after the failure, make -j2 ran '$(ran)', expected the render chunks and the assembly"
compare_runs
echo "PASS"
