#!/usr/bin/env bash
# Issue 8 acceptance: a shot run through Slurm gives the same files as a local run, and a killed
# surfacing task is all that a re-run resubmits.
#
#   farm_test.sh SOURCE_DIR BIN_DIR [SHOT_FILE]
#
# 1. starts a one-node Slurm cluster (slurm-wlm + munge) in a temporary folder, stopped by a trap
#    whatever happens;
# 2. runs the shot locally (the stage binaries in shot.mk's order) into TMP/local;
# 3. submits it to the cluster (pipeline/farm/submit.sh, 2 frames per surfacing task), cancels
#    one surfacing array task as soon as it runs, waits, and checks the status reports that
#    task killed with its frames and log;
# 4. re-runs the submission and checks it resubmits exactly that task's frames (plus the merge, the
#    render array over every frame in chunks of 2 and the assembly that depend on them), and
#    nothing of init or sim;
# 5. compares every cache, mesh, image and movie (VDB, VTU, GLB, edge breaks, PNG, MP4) byte for
#    byte (the edge break history without its header's input hash, which covers the sim's wall
#    times): frames rendered in chunks and assembled by another job equal a local mc-render run;
# 6. removes two rendered frames and the render manifest (what a failed render chunk leaves) and
#    checks the re-run submits only that chunk and the assembly, then compares again;
# 7. removes the sim's last frames and checkpoint (an interrupted sim) and checks the re-run
#    resumes from the checkpoint before them, then compares again.
# Prints the farm overhead it measured (submit-to-start latency, task vs local stage times).
# Exits 77 (ctest SKIP_RETURN_CODE) only when slurm-wlm or munge is not installed.
# FARM_TEST_KEEP=1 keeps the temporary folder for inspection.
set -euo pipefail

[ $# -ge 2 ] || { echo "usage: farm_test.sh SOURCE_DIR BIN_DIR [SHOT_FILE]" >&2; exit 2; }
src=$(cd "$1" && pwd)
bin=$(cd "$2" && pwd)
shot=${3:-$src/tests/farm/farm_shot.json}
farm=$src/pipeline/farm

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

tmp=$(mktemp -d "${TMPDIR:-/tmp}/mudcrack-farm-test.XXXXXX")
cluster=$tmp/slurm
cleanup() {
    local rc=$?
    bash "$farm/slurm_local_cluster.sh" stop "$cluster" || true
    if [ "${FARM_TEST_KEEP:-0}" = 1 ] || [ $rc -ne 0 ]; then
        echo "farm_test: kept $tmp (slurm logs in $cluster/log)"
        [ $rc -ne 0 ] && [ -d "$tmp/farm/farm_test/logs" ] && tail -n 5 "$tmp"/farm/farm_test/logs/*.log || true
    else
        rm -rf "$tmp"
    fi
}
trap cleanup EXIT

now() { date +%s.%N; }
elapsed() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.2f", b - a }'; }

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
    [ "$(jq -c '[.per_frame[] | [.frame, .boundary.faces, .broken_edges, .fragments]]' "$local_out/surface/manifest.json")" = \
      "$(jq -c '[.per_frame[] | [.frame, .boundary.faces, .broken_edges, .fragments]]' "$out/surface/manifest.json")" ] ||
        fail "surface/manifest.json per_frame entries differ"
    echo "   $compared files byte-identical"
}

echo "== starting a one-node Slurm cluster in $cluster"
bash "$farm/slurm_local_cluster.sh" start "$cluster"
export SLURM_CONF=$cluster/slurm.conf
cpus=$(sinfo -h -N -o %c | head -n 1)

# The sim is bitwise reproducible at a fixed thread count (mc-sim --resume's contract), so both
# runs use the same. One thread per task: on a busy 2-core machine a 2-thread sim of this small
# shot spends most of its time waiting at barriers (measured: 1.4 s vs 0.4 s).
threads=1
export FARM_SIM_CPUS=1 FARM_INIT_CPUS=1 FARM_RENDER_CPUS=1 FARM_SURFACE_CPUS=1 FARM_ASSEMBLE_CPUS=1
export FARM_SIM_MEM=2G FARM_INIT_MEM=2G FARM_SURFACE_MEM=1G FARM_RENDER_MEM=2G FARM_MERGE_MEM=256M FARM_ASSEMBLE_MEM=2G
unset MUDCRACK_PARTITION SLURM_PARTITION MUDCRACK_ACCOUNT SLURM_ACCOUNT FARM_THREADS FARM_SBATCH_ARGS FARM_RENDER_CHUNK

echo "== local run ($threads threads)"
local_out=$tmp/local/farm_test
declare -A local_seconds
for stage in $("$bin/mc-shot" stages "$shot"); do
    t0=$(now)
    "$bin/mc-$stage" --shot "$shot" --out "$local_out" --threads "$threads" --quiet >"$tmp/local.$stage.log" 2>&1 ||
        { cat "$tmp/local.$stage.log"; fail "local mc-$stage failed"; }
    local_seconds[$stage]=$(elapsed "$t0" "$(now)")
    echo "   mc-$stage: ${local_seconds[$stage]} s"
done

echo "== farm run, killing one surfacing task"
out=$tmp/farm/farm_test
t0=$(now)
bash "$farm/submit.sh" --shot "$shot" --out "$out" --bin "$bin" --chunk 2
jobs=$out/farm/jobs.tsv
# the victim: the array's second task (frames of a chunk that is neither the first nor the prep)
victim_line=$(awk -F'\t' '$1 == "surface" && $2 ~ /_2$/' "$jobs")
[ -n "$victim_line" ] || fail "no surfacing array task _2 in $jobs:
$(cat "$jobs")"
victim=$(cut -f2 <<<"$victim_line")
victim_frames=$(cut -f3 <<<"$victim_line")
victim_log=$(cut -f4 <<<"$victim_line")
victim_state=$out/farm/state/$(basename "$victim_log" .log)
deadline=$((SECONDS + 150))
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
# chunk -> the array)
st() { sed -n "s/^$2=//p" "$out/farm/state/$1"; }
submit_time=$(awk -F'\t' '$1 == "init" { print $5 }' "$jobs")
latency="$(elapsed "$submit_time" "$(st init start)")"
gaps="$(elapsed "$(st init end)" "$(st sim start)") $(elapsed "$(st sim end)" "$(st surface.0001-0002 start)")"
for task in surface.0003-0004 surface.0007-0008; do gaps="$gaps $(elapsed "$(st surface.0001-0002 end)" "$(st $task start)")"; done
task_seconds=$(for t in init sim surface.0001-0002 surface.0003-0004 surface.0007-0008; do
    elapsed "$(st $t start)" "$(st $t end)"; echo; done | awk '{ s += $1 } END { printf "%.2f", s }')

echo "== re-run: resubmits only frames $victim_frames"
resubmit=$(bash "$farm/submit.sh" --shot "$shot" --out "$out" --bin "$bin" --chunk 2 --wait) ||
    { echo "$resubmit"; fail "the re-run did not complete"; }
echo "$resubmit"
grep -q "last submission: surface frames $victim_frames (job $victim): KILLED; log $victim_log" <<<"$resubmit" ||
    fail "the re-run does not report the killed task with its frames and log"
stages_again=$(cut -f1,3 "$jobs" | tr '\t' ' ' | tr '\n' ',')
# every frame is rendered again (the merge rewrote the surfacing manifest), 2 frames per task
render_tasks=$(seq "$(jq -r .frames.start "$out/sim.params.json")" "$(jq -r .frames.end "$out/sim.params.json")" |
    awk '{ if (NR % 2) a = $1; else printf "render %d-%d,", a, $1 } END { if (NR % 2) printf "render %d-%d,", a, a }')
[ "$stages_again" = "surface $victim_frames,surface-merge -,${render_tasks}render-assemble -," ] ||
    fail "the re-run submitted '$stages_again', expected only surface $victim_frames, the merge, ${render_tasks} and the assembly"
render_task_seconds=$(for t in "$out"/farm/state/render.*; do
    elapsed "$(sed -n 's/^start=//p' "$t")" "$(sed -n 's/^end=//p' "$t")"; echo; done | awk '{ printf "%s ", $1 }')
assemble_seconds=$(elapsed "$(sed -n 's/^start=//p' "$out/farm/state/render-assemble")" "$(sed -n 's/^end=//p' "$out/farm/state/render-assemble")")
again=$(bash "$farm/submit.sh" --shot "$shot" --out "$out" --bin "$bin" --chunk 2)
grep -q "nothing submitted" <<<"$again" || fail "a third run submitted work: $again"

echo "== comparing outputs"
compare_outputs

echo "== a failed render chunk: the re-run renders only its frames, then assembles"
# what a render task killed during frame 6 leaves: frames 5 and 6 missing (a killed frame never
# reaches its name), no manifest (chunks remove it; the assembly never ran)
rm -f "$out/render/manifest.json" "$out/render/frame.0005.png" "$out/render/frame.0006.png"
bash "$farm/submit.sh" --shot "$shot" --out "$out" --bin "$bin" --chunk 2 --wait >"$tmp/render_again.txt" ||
    { cat "$tmp/render_again.txt"; fail "the render re-run did not complete"; }
cat "$tmp/render_again.txt"
[ "$(cut -f1,3 "$jobs" | tr '\t' ' ' | tr '\n' ',')" = "render 5-6,render-assemble -," ] ||
    fail "after losing frames 5-6, expected only render 5-6 and the assembly: $(cut -f1,3 "$jobs" | tr '\t' ' ' | tr '\n' ',')"
grep -E "^render +5-6 +[0-9_]+ +done " "$tmp/render_again.txt" >/dev/null || fail "status does not show render 5-6 done"
grep -E "^render-assemble +- +[0-9]+ +done " "$tmp/render_again.txt" >/dev/null || fail "status does not show the assembly done"
compare_outputs

echo "== an interrupted sim: the re-run resumes from its last checkpoint"
# what a sim killed during frame 7 leaves: caches and checkpoints up to frame 6, no manifest
rm -f "$out/sim/manifest.json" "$out/sim/particles.0007.vdb" "$out/sim/particles.0008.vdb" "$out/sim/checkpoint.0008.bin"
[ -f "$out/sim/checkpoint.0006.bin" ] || fail "no checkpoint.0006.bin to resume from"
bash "$farm/submit.sh" --shot "$shot" --out "$out" --bin "$bin" --chunk 2 --wait >"$tmp/resume.txt" ||
    { cat "$tmp/resume.txt"; fail "the resumed run did not complete"; }
[ "$(cut -f1 "$jobs" | sort -u | tr '\n' ' ')" = "render render-assemble sim surface surface-merge " ] ||
    fail "after removing the sim's last frames, expected sim, surface, merge, render and assembly jobs: $(cut -f1 "$jobs" | tr '\n' ' ')"
grep -q -- "--resume" "$out/logs/sim.log" && grep -q "resuming from .*checkpoint.0006.bin" "$out/logs/sim.log" ||
    fail "the sim did not resume from checkpoint.0006.bin: see $out/logs/sim.log"
compare_outputs

echo "== overhead (this machine, $cpus CPUs)"
echo "   submit to start (no dependency): $latency s"
echo "   dependency released to start: $gaps s"
echo "   task run times (init, sim, 3 of 4 surfacing chunks): $task_seconds s; local init + sim + surface: $(
    awk -v a="${local_seconds[init]}" -v b="${local_seconds[sim]}" -v c="${local_seconds[surface]}" 'BEGIN { printf "%.2f", a + b + c }') s"
echo "   render tasks (2 frames each): $render_task_seconds s; assembly: $assemble_seconds s; local mc-render: ${local_seconds[render]} s"
echo "   first farm run (all stages, one task killed): $first_run_seconds s; local run $(
    printf '%s\n' "${local_seconds[@]}" | awk '{ s += $1 } END { printf "%.2f", s }') s"
echo "PASS"
