#!/usr/bin/env bash
# The farm's promise: a shot run through Slurm gives the same files as a local run, and a
# killed surfacing task is all that a re-run resubmits.
#
#   farm_test.sh SOURCE_DIR BIN_DIR [SHOT_FILE]     (SHOT_FILE default: SOURCE_DIR/shots/fig8_c.json,
#                                                    cut by tests/short_shot.sh: 24 frames, 6 views,
#                                                    a quarter of a box source's footprint)
#
# 1. starts a one-node Slurm cluster (slurm-wlm + munge) in a temporary folder, stopped by a trap
#    whatever happens;
# 2. runs the shot locally (the stage binaries in shot.mk's order) into TMP/local;
# 3. submits it to the cluster (pipeline/farm/submit.sh, FARM_TEST_CHUNK frames per surfacing and
#    render task, default 8), cancels the surfacing array's second task (neither the first chunk
#    nor the first array task) as soon as it runs, waits, and checks the status reports that task
#    killed with its frames and log;
# 4. re-runs the submission and checks it resubmits exactly that task's frames (plus the merge, the
#    render array over every frame in chunks and the assembly that depend on them), and nothing of
#    init or sim;
# 5. compares every cache, mesh, image and movie (VDB, VTU, GLB, edge breaks, PNG, MP4) byte for
#    byte (the edge break history without its header's input hash, which covers the sim's wall
#    times): frames rendered in chunks and assembled by another job equal a local mc-render run;
#    and the checksums the sim, surface and render manifests record for them are the local run's;
# 6. removes the last two frames of the second render chunk and the render manifest (what a render
#    task killed during the first of them leaves) and checks the re-run submits only those frames
#    and the assembly, then compares again;
# 7. removes the sim's frames after its last checkpoint before the final frame, the later
#    checkpoints and the manifest (what a sim killed during the frame after that checkpoint
#    leaves) and checks the re-run resumes from that checkpoint, then compares again.
# Every frame number comes from the shot (its sim slice), the chunk files submit.sh wrote and the
# checkpoints the sim wrote. Prints the farm overhead it measured (submit-to-start latency, task vs
# local stage times).
# Exits 77 (ctest SKIP_RETURN_CODE) only when slurm-wlm or munge is not installed.
# FARM_TEST_KEEP=1 keeps the temporary folder for inspection.
set -euo pipefail

[ $# -ge 2 ] || { echo "usage: farm_test.sh SOURCE_DIR BIN_DIR [SHOT_FILE]" >&2; exit 2; }
src=$(cd "$1" && pwd)
bin=$(cd "$2" && pwd)
shot=${3:-$src/shots/fig8_c.json}
shot=$(cd "$(dirname "$shot")" && pwd)/$(basename "$shot")
farm=$src/pipeline/farm
name=$(basename "$shot" .json)
chunk=${FARM_TEST_CHUNK:-8}

if ! command -v slurmctld >/dev/null 2>&1 || ! command -v slurmd >/dev/null 2>&1; then
    echo "SKIPPED: slurm-wlm not installed (apt-get install slurm-wlm munge)"
    exit 77
fi
if ! command -v munged >/dev/null 2>&1; then
    echo "SKIPPED: munge not installed (apt-get install slurm-wlm munge)"
    exit 77
fi

fail() { echo "FAIL: $*" >&2; exit 1; }
command -v jq >/dev/null || fail "jq not found (apt-get install jq): the farm scripts need it"
for b in mc-shot mc-init mc-sim mc-surface mc-render; do
    [ -x "$bin/$b" ] || fail "$bin/$b: not built"
done
[ -f "$shot" ] || fail "$shot: no such shot file"
# frame chunking and file names exactly as submit.sh computes them
# shellcheck source=../../pipeline/farm/farm_lib.sh
. "$farm/farm_lib.sh"

tmp=$(mktemp -d "${TMPDIR:-/tmp}/mudcrack-farm-test.XXXXXX")
cluster=$tmp/slurm
cleanup() {
    local rc=$?
    bash "$farm/slurm_local_cluster.sh" stop "$cluster" || true
    if [ "${FARM_TEST_KEEP:-0}" = 1 ] || [ $rc -ne 0 ]; then
        echo "farm_test: kept $tmp (slurm logs in $cluster/log)"
        [ $rc -ne 0 ] && [ -d "$tmp/farm/$name/logs" ] && tail -n 5 "$tmp/farm/$name"/logs/*.log || true
    else
        rm -rf "$tmp"
    fi
}
trap cleanup EXIT
# shellcheck source=../short_shot.sh
. "$src/tests/short_shot.sh"
short_shot "$shot" >"$tmp/$name.json" || fail "$shot: cannot shorten it with jq"
shot=$tmp/$name.json

now() { date +%s.%N; }
elapsed() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.2f", b - a }'; }
# the stages and jobs.tsv of the last submission as "stage frames," pairs
submitted() { cut -f1,3 "$out/farm/jobs.tsv" | tr '\t' ' ' | tr '\n' ','; }
# "stage A-B," for each "A B" line on stdin
as_tasks() { awk -v stage="$1" '{ printf "%s %d-%d,", stage, $1, $2 }'; }

# every cache, mesh and image of the local run, byte for byte in the farm run, and no extra ones
compare_outputs() {
    local compared=0 file rel skip stage key
    while IFS= read -r -d '' file; do
        rel=${file#"$local_out"/}
        [ -f "$out/$rel" ] || fail "farm run lacks $rel"
        # edge_breaks.bin opens with a hash of the sim manifest, whose wall times differ between
        # runs: compare from the frame range on (frames, edge count, first break per edge, checksum)
        skip=0
        [ "$(basename "$rel")" = edge_breaks.bin ] && skip=16
        cmp -s -i "$skip" "$file" "$out/$rel" || fail "$rel differs between the local and the farm run"
        compared=$((compared + 1))
    done < <(find "$local_out" -type f \( -name '*.vdb' -o -name '*.vtu' -o -name '*.glb' -o -name '*.png' -o -name '*.mp4' \
        -o -name 'edge_breaks.bin' \) -print0)
    while IFS= read -r -d '' file; do
        rel=${file#"$out"/}
        [ -f "$local_out/$rel" ] || fail "farm run has $rel, the local run does not"
    done < <(find "$out"/{init,sim,surface,render} -type f \( -name '*.vdb' -o -name '*.vtu' -o -name '*.glb' \
        -o -name '*.png' -o -name '*.mp4' -o -name 'edge_breaks.bin' \) -print0)
    for stage in init sim surface render; do
        for key in .frames.first .frames.last .frames.count; do
            [ "$(jq "$key" "$local_out/$stage/manifest.json")" = "$(jq "$key" "$out/$stage/manifest.json")" ] ||
                fail "$stage/manifest.json $key differs"
        done
    done
    local entries='[.per_frame[] | [.frame, .boundary.faces, .broken_edges, .fragments, .boundary.crc32, .crack.crc32]]'
    [ "$(jq -c "$entries" "$local_out/surface/manifest.json")" = "$(jq -c "$entries" "$out/surface/manifest.json")" ] ||
        fail "surface/manifest.json per_frame entries differ"
    # the checksums readers verify: the same files, the same records
    [ "$(jq -c .caches "$local_out/sim/manifest.json")" = "$(jq -c .caches "$out/sim/manifest.json")" ] ||
        fail "sim/manifest.json /caches differ"
    [ "$(jq -c .images "$local_out/render/manifest.json")" = "$(jq -c .images "$out/render/manifest.json")" ] ||
        fail "render/manifest.json /images differ"
    echo "   $compared files byte-identical"
}

echo "== starting a one-node Slurm cluster in $cluster"
bash "$farm/slurm_local_cluster.sh" start "$cluster"
export SLURM_CONF=$cluster/slurm.conf
cpus=$(sinfo -h -N -o %c | head -n 1)

# The sim is bitwise reproducible at a fixed thread count (mc-sim --resume's contract), so both
# runs use the same. One thread per task: per-frame tasks run one per CPU, and the sim, alone on
# the node, runs at nearly the same speed as with two on a busy 2-core machine.
threads=1
export FARM_SIM_CPUS=1 FARM_INIT_CPUS=1 FARM_RENDER_CPUS=1 FARM_SURFACE_CPUS=1 FARM_ASSEMBLE_CPUS=1
export FARM_SIM_MEM=2G FARM_INIT_MEM=2G FARM_SURFACE_MEM=1G FARM_RENDER_MEM=2G FARM_MERGE_MEM=256M FARM_ASSEMBLE_MEM=2G
unset MUDCRACK_PARTITION SLURM_PARTITION MUDCRACK_ACCOUNT SLURM_ACCOUNT FARM_THREADS FARM_SBATCH_ARGS FARM_RENDER_CHUNK

echo "== local run of $name ($threads threads)"
local_out=$tmp/local/$name
mkdir -p "$local_out"
declare -A local_seconds
stages=$("$bin/mc-shot" stages "$shot")
for stage in $stages; do
    "$bin/mc-shot" slice "$shot" "$stage" --out "$local_out/$stage.params.json"
done
[[ " $stages " == *" surface "* && " $stages " == *" render "* ]] ||
    fail "$shot: runs '$stages'; the farm test needs a shot with surfacing and rendering"
frame_first=$(jq -r .frames.start "$local_out/sim.params.json")
frame_last=$(jq -r .frames.end "$local_out/sim.params.json")
# the surfacing chunks submit.sh makes: the first one (the break history), then the array
mapfile -t surface_chunks < <(seq "$frame_first" "$frame_last" | farm_chunk_frames "$chunk")
[ ${#surface_chunks[@]} -ge 3 ] ||
    fail "frames $frame_first-$frame_last in chunks of $chunk: ${#surface_chunks[@]} surfacing tasks, the test needs 3 (FARM_TEST_CHUNK)"
echo "   frames $frame_first-$frame_last, $chunk per surfacing and render task: ${#surface_chunks[@]} surfacing tasks"
for stage in $stages; do
    t0=$(now)
    "$bin/mc-$stage" --shot "$shot" --out "$local_out" --threads "$threads" --quiet >"$tmp/local.$stage.log" 2>&1 ||
        { cat "$tmp/local.$stage.log"; fail "local mc-$stage failed"; }
    local_seconds[$stage]=$(elapsed "$t0" "$(now)")
    echo "   mc-$stage: ${local_seconds[$stage]} s"
done

echo "== farm run, killing one surfacing task"
out=$tmp/farm/$name
t0=$(now)
bash "$farm/submit.sh" --shot "$shot" --out "$out" --bin "$bin" --chunk "$chunk"
jobs=$out/farm/jobs.tsv
cp "$jobs" "$tmp/jobs.first.tsv"
[ "$(submitted)" = "init -,sim $frame_first-$frame_last,$(printf '%s\n' "${surface_chunks[@]}" | as_tasks surface)surface-merge -,$(
    printf '%s\n' "${surface_chunks[@]}" | as_tasks render)render-assemble -," ] ||
    fail "the first submission is not init, sim, ${#surface_chunks[@]} surfacing tasks, the merge, the render array and the assembly: $(submitted)"
# the victim: the array's second task, frames of a chunk that is neither the first nor the prep
victim_line=$(awk -F'\t' '$1 == "surface" && $2 ~ /_2$/' "$jobs")
[ -n "$victim_line" ] || fail "no surfacing array task _2 in $jobs:
$(cat "$jobs")"
victim=$(cut -f2 <<<"$victim_line")
victim_frames=$(cut -f3 <<<"$victim_line")
victim_log=$(cut -f4 <<<"$victim_line")
[ "$victim_frames" = "$(tr ' ' - <<<"${surface_chunks[2]}")" ] ||
    fail "surfacing array task _2 runs frames $victim_frames, expected the third chunk ${surface_chunks[2]}"
victim_state=$out/farm/state/$(basename "$victim_log" .log)
# the sim comes first: allow it the local sim time plus margin before giving up
deadline=$((SECONDS + 120 + 3 * ${local_seconds[sim]%.*}))
# running = its task.sh has started (and set its TERM trap), not only allocated
until grep -qx "job=$victim" "$victim_state" 2>/dev/null; do
    [ $SECONDS -lt $deadline ] || fail "surfacing task $victim never ran"
    [ -n "$(squeue -h -r -j "$victim" -o %T 2>/dev/null)" ] || fail "surfacing task $victim left the queue before it could be cancelled"
    sleep 0.02
done
grep -qx "status=running" "$victim_state" || fail "surfacing task $victim finished before it could be cancelled"
scancel "$victim"
echo "   cancelled $victim (frames $victim_frames) while running"
while [ -n "$(squeue -h -r -o %i)" ]; do sleep 0.2; done
status=$(bash "$farm/status.sh" --out "$out" --check) && rc=0 || rc=$?
echo "$status"
[ $rc -eq 1 ] || fail "status --check returned $rc after a killed task, expected 1"
grep -E "^surface +$victim_frames +$victim +KILLED .*$victim_log\$" <<<"$status" >/dev/null ||
    fail "status does not report $victim (frames $victim_frames) killed with its log $victim_log"
first_run_seconds=$(elapsed "$t0" "$(now)")
# the scheduling overhead, from the tasks' own clocks: submit to start of the first job, and
# from the end of a job to the start of the one waiting on it (init -> sim -> first surfacing
# chunk -> the array's first task)
st() { sed -n "s/^$2=//p" "$out/farm/state/$1"; }
# a chunk is "A B": split on purpose into farm_task_name's two frame arguments
# shellcheck disable=SC2086
prep_task=$(farm_task_name surface ${surface_chunks[0]})
# shellcheck disable=SC2086
array_first_task=$(farm_task_name surface ${surface_chunks[1]})
submit_time=$(awk -F'\t' '$1 == "init" { print $5 }' "$jobs")
latency="$(elapsed "$submit_time" "$(st init start)")"
gaps="$(elapsed "$(st init end)" "$(st sim start)") $(elapsed "$(st sim end)" "$(st "$prep_task" start)") $(
    elapsed "$(st "$prep_task" end)" "$(st "$array_first_task" start)")"
# run times of init, the sim and every surfacing task that was not killed
surface_tasks=$(awk -F'\t' -v victim="$victim" '$1 == "surface" && $2 != victim { n = split($4, p, "/"); sub(/\.log$/, "", p[n]); print p[n] }' "$jobs")
task_seconds=$(for t in init sim $surface_tasks; do
    elapsed "$(st "$t" start)" "$(st "$t" end)"; echo; done | awk '{ s += $1 } END { printf "%.2f", s }')
surface_task_count=$(wc -w <<<"$surface_tasks")
sim_task_seconds=$(elapsed "$(st sim start)" "$(st sim end)")

echo "== re-run: resubmits only frames $victim_frames"
resubmit=$(bash "$farm/submit.sh" --shot "$shot" --out "$out" --bin "$bin" --chunk "$chunk" --wait) ||
    { echo "$resubmit"; fail "the re-run did not complete"; }
echo "$resubmit"
grep -q "last submission: surface frames $victim_frames (job $victim): KILLED; log $victim_log" <<<"$resubmit" ||
    fail "the re-run does not report the killed task with its frames and log"
# every frame is rendered again (the merge rewrote the surfacing manifest), in chunks
render_tasks=$(printf '%s\n' "${surface_chunks[@]}" | as_tasks render)
[ "$(submitted)" = "surface $victim_frames,surface-merge -,${render_tasks}render-assemble -," ] ||
    fail "the re-run submitted '$(submitted)', expected only surface $victim_frames, the merge, ${render_tasks} and the assembly"
render_task_seconds=$(for t in "$out"/farm/state/render.*; do
    elapsed "$(sed -n 's/^start=//p' "$t")" "$(sed -n 's/^end=//p' "$t")"; echo; done | awk '{ printf "%s ", $1 }')
assemble_seconds=$(elapsed "$(st render-assemble start)" "$(st render-assemble end)")
again=$(bash "$farm/submit.sh" --shot "$shot" --out "$out" --bin "$bin" --chunk "$chunk")
grep -q "nothing submitted" <<<"$again" || fail "a third run submitted work: $again"

echo "== comparing outputs"
compare_outputs

# what a render task killed during frame K of its chunk A-B leaves: frames K..B missing (a killed
# frame never reaches its name), no manifest (chunks remove it; the assembly never ran); K is the
# second-to-last frame of the second chunk
read -r ra rb < <(sed -n 2p "$out/farm/render.chunks")
[ -n "${rb:-}" ] || fail "no second render chunk in $out/farm/render.chunks"
rk=$((rb > ra ? rb - 1 : rb))
echo "== a failed render chunk ($ra-$rb, killed at frame $rk): the re-run renders only frames $rk-$rb, then assembles"
rm -f "$out/render/manifest.json"
for ((n = rk; n <= rb; n++)); do rm -f "$(farm_frame_file "$out/render" frame "$n" png)"; done
bash "$farm/submit.sh" --shot "$shot" --out "$out" --bin "$bin" --chunk "$chunk" --wait >"$tmp/render_again.txt" ||
    { cat "$tmp/render_again.txt"; fail "the render re-run did not complete"; }
cat "$tmp/render_again.txt"
[ "$(submitted)" = "render $rk-$rb,render-assemble -," ] ||
    fail "after losing frames $rk-$rb, expected only render $rk-$rb and the assembly: $(submitted)"
grep -E "^render +$rk-$rb +[0-9_]+ +done " "$tmp/render_again.txt" >/dev/null || fail "status does not show render $rk-$rb done"
grep -E "^render-assemble +- +[0-9]+ +done " "$tmp/render_again.txt" >/dev/null || fail "status does not show the assembly done"
compare_outputs

# what a sim killed during the frame after checkpoint C leaves: caches and checkpoints up to C,
# no manifest. C is the last checkpoint the sim wrote before its final frame.
mapfile -t checkpoint_frames < <(find "$out/sim" -name 'checkpoint.*.bin' -printf '%f\n' |
    sed -n 's/^checkpoint\.0*\([0-9][0-9]*\)\.bin$/\1/p' | sort -n)
resume_frame=""
for c in "${checkpoint_frames[@]+"${checkpoint_frames[@]}"}"; do [ "$c" -lt "$frame_last" ] && resume_frame=$c; done
[ -n "$resume_frame" ] || fail "the sim wrote no checkpoint before its last frame $frame_last (checkpoints: ${checkpoint_frames[*]:-none}): set /sim/checkpoint_every in $shot"
resume_checkpoint=$(printf 'checkpoint.%04d.bin' "$resume_frame")
echo "== an interrupted sim (killed in frame $((resume_frame + 1))): the re-run resumes from $resume_checkpoint"
rm -f "$out/sim/manifest.json"
for ((n = resume_frame + 1; n <= frame_last; n++)); do
    rm -f "$(farm_frame_file "$out/sim" particles "$n" vdb)" "$(farm_frame_file "$out/sim" checkpoint "$n" bin)"
done
bash "$farm/submit.sh" --shot "$shot" --out "$out" --bin "$bin" --chunk "$chunk" --wait >"$tmp/resume.txt" ||
    { cat "$tmp/resume.txt"; fail "the resumed run did not complete"; }
[ "$(submitted)" = "sim $frame_first-$frame_last,$(printf '%s\n' "${surface_chunks[@]}" | as_tasks surface)surface-merge -,${render_tasks}render-assemble -," ] ||
    fail "after removing the sim's last frames, expected the sim, every surfacing and render task, the merge and the assembly: $(submitted)"
grep -q -- "--resume" "$out/logs/sim.log" && grep -q "resuming from .*$resume_checkpoint" "$out/logs/sim.log" ||
    fail "the sim did not resume from $resume_checkpoint: see $out/logs/sim.log"
[ "$(jq .resumed_from_frame "$out/sim/manifest.json")" = "$resume_frame" ] ||
    fail "sim/manifest.json resumed_from_frame is $(jq .resumed_from_frame "$out/sim/manifest.json"), expected $resume_frame"
resumed_sim_seconds=$(elapsed "$(st sim start)" "$(st sim end)")
compare_outputs

echo "== overhead (this machine, $cpus CPUs; shot $name, frames $frame_first-$frame_last, $chunk frames per task)"
echo "   submit to start (no dependency): $latency s"
echo "   dependency released to start (init->sim, sim->first surfacing chunk, first chunk->array): $gaps s"
echo "   task run times (init, sim, $surface_task_count of ${#surface_chunks[@]} surfacing chunks): $task_seconds s; local init + sim + surface: $(
    awk -v a="${local_seconds[init]}" -v b="${local_seconds[sim]}" -v c="${local_seconds[surface]}" 'BEGIN { printf "%.2f", a + b + c }') s"
echo "   sim task: $sim_task_seconds s (local mc-sim ${local_seconds[sim]} s); resumed from frame $resume_frame: $resumed_sim_seconds s"
echo "   render tasks ($chunk frames each): $render_task_seconds s; assembly: $assemble_seconds s; local mc-render: ${local_seconds[render]} s"
echo "   first farm run, submit to last task (init, sim, surfacing; the killed task cancels the merge and render): $first_run_seconds s"
echo "   local run: $(printf '%s\n' "${local_seconds[@]}" | awk '{ s += $1 } END { printf "%.2f", s }') s; whole test so far: $SECONDS s"
echo "PASS"
