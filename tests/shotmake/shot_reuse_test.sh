#!/usr/bin/env bash
# Shared caches (/reuse, as fig9 reuses fig8_c): pipeline/shot.mk run the way the root
# Makefile's `shot` target runs it, on two tiny shots derived from the demo shot in a temporary
# shots folder:
#
#   shot_reuse_test.sh SOURCE_DIR BIN_DIR [SHOT_FILE]     (SHOT_FILE default: SOURCE_DIR/shots/demo.json)
#
# base.json is the demo at a coarse spacing, 4 frames, small previews; look.json is base.json
# with "reuse": "base" and another render color mode (a render key only). Checked:
# 1. mc-shot validates /reuse (an existing other shot of the folder, not itself, no chains) and
#    keeps it out of every slice: look's init, sim and surface slices equal base's, render differs;
# 2. after base is made, `make shot` of look runs only look's render; look/init, sim and surface
#    are links to ../base/..., look's render outputs exist, base's manifests are untouched;
# 3. a second run does nothing (-j1 and -j2);
# 3b. cut.json (look with the wang2019 surfacing, as fig10_wang2019 reuses fig10_ours) runs only
#    its surfacing and render under make -j2, reading base's init and sim through links;
# 4. a sim key edited in both shots (slices still identical) re-runs base's sim and surfacing
#    (not its render) and look's render, under make -j2 (render chunks reading the linked surface);
# 5. a sim key edited in look only: its sim is no longer shared, the links of sim and surface are
#    removed and look runs its own sim, surfacing and render; base's files are untouched;
# 6. FARM=slurm refuses a reuse shot; `make clean-shot` of look removes its folder, not base's.
# SHOT_MAKE_TEST_KEEP=1 keeps the temporary folder.
set -euo pipefail

# shellcheck source=make_test_lib.sh
. "$(dirname "${BASH_SOURCE[0]}")/make_test_lib.sh"
make_test_setup shot_reuse_test demo "$@"
mkdir -p "$tmp/shots"
base=$tmp/shots/base.json look=$tmp/shots/look.json out=$tmp/out

# edit FILE SED_SCRIPT WHAT: sed -i that must change the file
edit() {
    local before
    before=$(cat "$1")
    sed -i "$2" "$1"
    [ "$(cat "$1")" != "$before" ] || fail "$1: '$2' changed nothing ($3)"
}
# the tiny base: the disc of a jittered 0.025 m lattice (37 x 3 x 37) in place of the demo's
# Mesh_3 fill, on a 0.05 m grid, 4 frames, 160x90 previews, 4 views
cp "$shot_src" "$base"
edit "$base" 's/"name": "demo"/"name": "base"/' "the name"
edit "$base" 's/"lattice": "mesh",/"spacing": 0.025, "lattice": "jittered",/' "the box's lattice"
edit "$base" 's/"h": 0.02,/"h": 0.05,/' "the grid spacing"
edit "$base" 's/"end": 36,/"end": 4,/' "the frame range"
edit "$base" 's/"resolution": \[640, 360\]/"resolution": [160, 90]/' "the resolution"
edit "$base" 's/"views": 12/"views": 4/' "the turntable"
# the look: the same shot in the hardening colors, reusing base (the key right after the name)
cp "$base" "$look"
edit "$look" 's|"name": "base",|"name": "look",\n  // shares the stages whose slices equal base'"'"'s\n  "reuse": "base",|' "the reuse key"
edit "$look" 's/"color_mode": "moisture"/"color_mode": "hardening"/' "the color mode"

echo "== /reuse is validated and in no slice"
"$bin/mc-shot" validate "$look" >/dev/null || fail "mc-shot validate $look failed"
for stage in init sim surface render; do
    "$bin/mc-shot" slice "$base" $stage >"$tmp/base.$stage" && "$bin/mc-shot" slice "$look" $stage >"$tmp/look.$stage" ||
        fail "mc-shot slice $stage failed"
    ! grep -q reuse "$tmp/look.$stage" || fail "look's $stage slice holds /reuse"
done
for stage in init sim surface; do
    cmp -s "$tmp/base.$stage" "$tmp/look.$stage" || fail "look's $stage slice differs from base's"
done
! cmp -s "$tmp/base.render" "$tmp/look.render" || fail "look's render slice equals base's (the color mode differs)"
# refused: itself, a missing shot, a path, and a chain (a shot that reuses a shot that reuses)
expect_refused() {  # FILE EXPECTED_TEXT
    if "$bin/mc-shot" validate "$1" >"$tmp/validate.txt" 2>&1; then fail "$1: /reuse accepted: $(cat "$tmp/validate.txt")"; fi
    grep -q -- "$2" "$tmp/validate.txt" || fail "$1: the message does not say '$2': $(cat "$tmp/validate.txt")"
}
sed 's/"reuse": "base"/"reuse": "bad_self"/' "$look" >"$tmp/shots/bad_self.json"
expect_refused "$tmp/shots/bad_self.json" '/reuse = "bad_self": must name another shot, not this one'
sed 's/"reuse": "base"/"reuse": "nothere"/' "$look" >"$tmp/shots/bad_missing.json"
expect_refused "$tmp/shots/bad_missing.json" "/reuse = \"nothere\": no such shot (looked for $tmp/shots/nothere.json"
sed 's|"reuse": "base"|"reuse": "../shots/base"|' "$look" >"$tmp/shots/bad_path.json"
expect_refused "$tmp/shots/bad_path.json" '/reuse = "../shots/base": must be the name of another shot in this folder'
sed 's/"reuse": "base"/"reuse": "look"/' "$look" >"$tmp/shots/bad_chain.json"
expect_refused "$tmp/shots/bad_chain.json" '/reuse = "look": must name a shot that does not set /reuse itself'
rm "$tmp/shots"/bad_*.json

# shot_make NAME [MAKE_ARGS...]: the root Makefile's `shot` recipe for shots/NAME.json, one
# thread per stage; output in $tmp/make.txt
shot_make() {
    local name=$1
    shift
    make --no-print-directory -C "$src" -f Makefile -f pipeline/shot.mk shot-run shot-summary SHOT="$name" \
        SHOT_FILE="$tmp/shots/$name.json" OUT="$out" BUILD="$(dirname "$bin")" BIN="$bin" THREADS=1 "$@" \
        >"$tmp/make.txt" 2>&1
}
# what a make run ran, one "shot:stage" per stage binary or chunk task: "base:mc-sim,look:render-chunk,"
ran() {
    { grep -E -o '/mc-(init|sim|surface|render) --shot [^ ]+' "$tmp/make.txt" |
          sed -E 's|^/(mc-[a-z]+) --shot .*/([^/]+)\.json$|\2:\1|'
      grep -E -o '^mudcrack: [a-z]+: [a-z-]+ ' "$tmp/make.txt" | sed -E 's/^mudcrack: ([a-z]+): ([a-z-]+) $/\1:\2/'
    } | tr '\n' ',' || true
}
mtimes() { stat -c '%n %Y.%y' "$out/$1"/{init,sim,surface,render}/manifest.json; }
# every file under base's stage folders, with its size and mtime
base_files() { find "$out/base"/{init,sim,surface,render} -type f -printf '%p %s %T@\n' | sort; }
is_link_to_base() { [ -L "$out/look/$1" ] && [ "$(readlink "$out/look/$1")" = "../base/$1" ]; }

echo "== make shot base"
shot_make base || { cat "$tmp/make.txt"; fail "make shot base failed"; }
[ "$(ran)" = "base:mc-init,base:mc-sim,base:mc-surface,base:mc-render," ] || { cat "$tmp/make.txt"; fail "make shot base ran '$(ran)'"; }

echo "== make shot look: only its render runs"
before=$(base_files)
shot_make look || { cat "$tmp/make.txt"; fail "make shot look failed"; }
[ "$(ran)" = "look:mc-render," ] || { cat "$tmp/make.txt"; fail "make shot look ran '$(ran)', expected look's mc-render only"; }
for stage in init sim surface; do
    is_link_to_base $stage || fail "$out/look/$stage is not a link to ../base/$stage: $(ls -ld "$out/look/$stage")"
    grep -q "mudcrack: look/$stage -> ../base/$stage" "$tmp/make.txt" || { cat "$tmp/make.txt"; fail "make did not report the $stage link"; }
done
[ -d "$out/look/render" ] && [ ! -L "$out/look/render" ] || fail "$out/look/render is not look's own folder"
for f in manifest.json frame.0001.png frame.0004.png turntable.0001.png contact_sheet.png preview.mp4; do
    [ -s "$out/look/render/$f" ] || fail "look's render did not write $f"
done
[ "$(jq -r .color_mode "$out/look/render/manifest.json")" = hardening ] ||
    fail "look's render manifest: color_mode $(jq -r .color_mode "$out/look/render/manifest.json"), expected hardening"
! cmp -s "$out/look/render/frame.0004.png" "$out/base/render/frame.0004.png" || fail "look rendered base's colors"
[ "$(base_files)" = "$before" ] || fail "make shot look changed base's files"
tail -n 4 "$tmp/make.txt" | cut -c1-8 | tr -s ' \n' ' ' | grep -qx 'init sim surface render ' ||
    { cat "$tmp/make.txt"; fail "make shot look does not end with the summary table"; }

echo "== a second run does nothing"
before=$(mtimes look; mtimes base)
for jobs in -j1 -j2; do
    shot_make look $jobs || { cat "$tmp/make.txt"; fail "the second make ($jobs) failed"; }
    [ -z "$(ran)" ] || fail "the second make ($jobs) ran: $(ran)"
    [ "$(mtimes look; mtimes base)" = "$before" ] || fail "the second make ($jobs) rewrote a manifest"
done

echo "== make -j2 shot cut (another surfacing of base's sim): its surfacing and render only"
# as fig10_wang2019 reuses fig10_ours: the surfacing chunks read the linked init and sim
sed -e 's/"name": "look"/"name": "cut"/' -e 's/"mode": "\(ours\|plates\)"/"mode": "wang2019"/' "$look" >"$tmp/shots/cut.json"
grep -q '"mode": "wang2019"' "$tmp/shots/cut.json" || fail "cut.json: the surfacing mode was not edited"
before=$(base_files)
shot_make cut -j2 || { cat "$tmp/make.txt"; fail "make -j2 shot cut failed"; }
got=$(ran)
[[ $got == cut:surface-prep,*cut:surface-merge,*cut:render-assemble, && $got != *base:* && $got != *mc-init* && $got != *mc-sim* ]] ||
    { cat "$tmp/make.txt"; fail "make -j2 shot cut ran '$got', expected cut's surfacing and render chunks only"; }
for stage in init sim; do
    [ "$(readlink "$out/cut/$stage")" = "../base/$stage" ] || fail "$out/cut/$stage is not a link to ../base/$stage"
done
for stage in surface render; do
    [ -f "$out/cut/$stage/manifest.json" ] && [ ! -L "$out/cut/$stage" ] || fail "$out/cut/$stage is not cut's own stage"
done
[ "$(jq -r .mode "$out/cut/surface/manifest.json")" = wang2019 ] || fail "cut's surface manifest is not the wang2019 surfacing"
[ "$(base_files)" = "$before" ] || fail "make shot cut changed base's files"

echo "== a sim key edited in both shots: base's sim and surfacing, then look's render (make -j2)"
for f in "$base" "$look"; do edit "$f" 's/"D": 0.01,/"D": 0.0066,/' "the diffusivity"; done
base_render=$(stat -c %Y.%y "$out/base/render/manifest.json")
shot_make look -j2 || { cat "$tmp/make.txt"; fail "make -j2 after the sim edit failed"; }
got=$(ran)
[[ $got == base:mc-sim,base:surface-prep,* ]] || { cat "$tmp/make.txt"; fail "after the sim edit make ran '$got': expected base's sim, then its surfacing"; }
[[ $got != *mc-init* && $got != *look:mc-sim* && $got != *look:surface* ]] || fail "after the sim edit make ran '$got'"
[[ $got == *look:render-chunk*look:render-assemble, ]] || { cat "$tmp/make.txt"; fail "after the sim edit make ran '$got': no render of look in chunks"; }
[ "$(stat -c %Y.%y "$out/base/render/manifest.json")" = "$base_render" ] || fail "the look's make re-rendered base"
for stage in init sim surface; do is_link_to_base $stage || fail "look/$stage is no longer a link to base's"; done
[ "$(jq -r .inputs.surface.slice_hash "$out/look/render/manifest.json")" = \
  "$(jq -r .shot_slice_hash "$out/base/surface/manifest.json")" ] || fail "look's render did not read base's new surfacing"

echo "== a sim key edited in look only: its sim is its own again"
edit "$look" 's/"D": 0.0066,/"D": 0.0061,/' "the diffusivity"
before=$(base_files)
shot_make look || { cat "$tmp/make.txt"; fail "make after the look-only sim edit failed"; }
[ "$(ran)" = "look:mc-sim,look:mc-surface,look:mc-render," ] ||
    { cat "$tmp/make.txt"; fail "after the look-only sim edit make ran '$(ran)', expected look's sim, surface and render"; }
is_link_to_base init || fail "look/init is not a link to base's any more (its slice still matches)"
for stage in sim surface render; do
    [ -d "$out/look/$stage" ] && [ ! -L "$out/look/$stage" ] || fail "look/$stage is not look's own folder"
done
grep -q "mudcrack: look/sim: removed the link to ../base/sim" "$tmp/make.txt" || { cat "$tmp/make.txt"; fail "make did not report the removed sim link"; }
[ "$(base_files)" = "$before" ] || fail "look's own sim changed base's files"

echo "== FARM=slurm refuses a reuse shot"
if make --no-print-directory -C "$src" -f Makefile -f pipeline/shot.mk farm-submit SHOT=look SHOT_FILE="$look" \
        OUT="$out" BUILD="$(dirname "$bin")" BIN="$bin" >"$tmp/make.txt" 2>&1; then
    cat "$tmp/make.txt"; fail "farm-submit accepted a reuse shot"
fi
grep -q 'FARM=slurm does not support /reuse = "base"' "$tmp/make.txt" || { cat "$tmp/make.txt"; fail "farm-submit's refusal does not say why"; }

echo "== make clean-shot SHOT=look leaves base intact (look/init is still a link)"
before=$(base_files)
make --no-print-directory -C "$src" clean-shot SHOT=look OUT="$out" >"$tmp/make.txt" 2>&1 || { cat "$tmp/make.txt"; fail "make clean-shot failed"; }
[ ! -e "$out/look" ] && [ ! -L "$out/look" ] || fail "make clean-shot left $out/look"
[ "$(base_files)" = "$before" ] || fail "make clean-shot SHOT=look changed base's files"
echo "PASS"
