#!/usr/bin/env bash
# Submits what a shot still needs to a Slurm cluster: init and sim as jobs, surfacing as an array
# over frame chunks (after a first chunk that computes the break history), a merge of the
# surfacing manifest, the render as an array over frame chunks (mc-render --frames; after the
# merge, whose manifest every chunk reads), then the render assembly (mc-render --assemble:
# turntable, contact sheet, movies, manifest); chained with afterok dependencies so nothing starts
# before its inputs exist. What is already done is not submitted: a stage is done when its
# manifest is newer than its inputs (make's rule, as in pipeline/shot.mk), a surfacing frame when
# its mesh is, a rendered frame when its PNG is; an interrupted sim resumes from its last
# checkpoint. Re-running after a failure therefore resubmits only the failed or missing work.
#
#   submit.sh --shot shots/demo.json --out out/demo --bin build/bin [--chunk 4] [--wait] [--dry-run]
#
# Environment (all optional):
#   MUDCRACK_PARTITION or SLURM_PARTITION    partition (default: the cluster's default)
#   MUDCRACK_ACCOUNT or SLURM_ACCOUNT        account
#   FARM_CHUNK                               frames per surfacing task (default 4; --chunk wins)
#   FARM_RENDER_CHUNK                        frames per render task (default: as FARM_CHUNK)
#   FARM_<STAGE>_CPUS / _MEM / _TIME         per stage (INIT, SIM, SURFACE, MERGE, RENDER,
#                                            ASSEMBLE):
#                                            CPUs per task, --mem, --time (defaults below)
#   FARM_THREADS                             --threads for every stage (default: the task's CPUs)
#   FARM_SBATCH_ARGS                         extra sbatch arguments, e.g. "--qos=short"
set -euo pipefail

FARM_PROGRAM=mc-farm
FARM_DIR=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
# shellcheck source=farm_lib.sh
. "$FARM_DIR/farm_lib.sh"

usage() {
    sed -n '/^#   submit.sh/p' "${BASH_SOURCE[0]}" | sed 's/^#   /usage: /' >&2
    exit 2
}

shot="" out="" bin="" chunk=${FARM_CHUNK:-4} wait=0 dry=0
while [ $# -gt 0 ]; do
    case $1 in
        --shot) shot=$2; shift 2 ;;
        --out) out=$2; shift 2 ;;
        --bin) bin=$2; shift 2 ;;
        --chunk) chunk=$2; shift 2 ;;
        --wait) wait=1; shift ;;
        --dry-run) dry=1; shift ;;
        *) usage ;;
    esac
done
[ -n "$shot" ] && [ -n "$out" ] && [ -n "$bin" ] || usage
[[ $chunk =~ ^[1-9][0-9]*$ ]] || farm_die "--chunk / FARM_CHUNK = '$chunk': expected a whole number >= 1"
render_chunk=${FARM_RENDER_CHUNK:-$chunk}
[[ $render_chunk =~ ^[1-9][0-9]*$ ]] || farm_die "FARM_RENDER_CHUNK = '$render_chunk': expected a whole number >= 1"
[ -f "$shot" ] || farm_die "$shot: no such shot file"
for tool in sbatch squeue jq flock; do
    command -v "$tool" >/dev/null || farm_die "$tool not found (Slurm clients: slurm-client; jq: jq)"
done
# compute nodes see the same paths (a shared filesystem), so every path handed to them is absolute
mkdir -p "$out"
shot=$(cd "$(dirname "$shot")" && pwd)/$(basename "$shot")
out=$(cd "$out" && pwd)
bin=$(cd "$bin" && pwd)
farm=$out/farm
mkdir -p "$farm/state" "$out/logs/slurm"

# -- one submission at a time ---------------------------------------------------------------------
exec 9>"$farm/submit.lock"
flock -n 9 || farm_die "$out: another submission of this shot is in progress"
if [ -f "$farm/jobs.tsv" ]; then
    in_flight=$(farm_in_queue "$farm/jobs.tsv" | tr '\n' ' ')
    [ -z "$in_flight" ] || farm_die "jobs of the last submission are still queued or running: $in_flight
  (see: make farm-status; cancel with: scancel $in_flight)"
    # say what went wrong last time before resubmitting it
    bash "$FARM_DIR/status.sh" --out "$out" --failures-only || true
    [ $dry -eq 1 ] || mv "$farm/jobs.tsv" "$farm/jobs.$(date +%Y%m%dT%H%M%S).tsv"
fi

# -- the slices make compares against (only rewritten when they change) ---------------------------
stages=$("$bin/mc-shot" stages "$shot")
for s in $stages; do
    err=$("$bin/mc-shot" slice "$shot" "$s" --out "$out/$s.params.json" 2>&1 >/dev/null) || farm_die "$err"
done
has_stage() { [[ " $stages " == *" $1 "* ]]; }

# -- what is not done -----------------------------------------------------------------------------
run_init=0 run_sim=0 resume=0 surface_prep="" surface_chunks=() run_merge=0 render_chunks=() run_assemble=0
farm_fresh "$out/init/manifest.json" "$out/init.params.json" "$bin/mc-init" || run_init=1
if [ $run_init -eq 1 ] || ! farm_fresh "$out/sim/manifest.json" "$out/init/manifest.json" "$out/sim.params.json" "$bin/mc-sim"; then
    run_sim=1
    # like shot.mk: continue from the checkpoints of an interrupted run of the same init
    if [ $run_init -eq 0 ] && compgen -G "$out/sim/checkpoint.*.bin" >/dev/null; then resume=1; fi
fi
frame_first=$(jq -r .frames.start "$out/sim.params.json")
frame_last=$(jq -r .frames.end "$out/sim.params.json")

if has_stage surface; then
    inputs=("$out/sim/manifest.json" "$out/surface.params.json" "$bin/mc-surface")
    format=$(jq -r '.surfacing.format // "glb"' "$out/surface.params.json")
    missing=()
    if [ $run_sim -eq 1 ] || ! farm_fresh "$farm/surface-base/manifest.json" "${inputs[@]}"; then
        # no usable break history: everything is surfaced again, unless a local run did it all
        if [ $run_sim -eq 1 ] || ! farm_fresh "$out/surface/manifest.json" "${inputs[@]}"; then
            mapfile -t missing < <(seq "$frame_first" "$frame_last")
            [ ${#missing[@]} -gt 0 ] || farm_die "no frames"
        fi
        base_needed=1
    else
        base_needed=0
        for ((n = frame_first; n <= frame_last; n++)); do
            farm_fresh "$(farm_frame_file "$out/surface" boundary "$n" "$format")" "${inputs[@]}" || missing+=("$n")
        done
    fi
    mapfile -t chunks < <(printf '%s\n' "${missing[@]+"${missing[@]}"}" | sed '/^$/d' | farm_chunk_frames "$chunk")
    if [ ${#chunks[@]} -gt 0 ]; then
        run_merge=1
        if [ $base_needed -eq 1 ]; then surface_prep=${chunks[0]}; chunks=("${chunks[@]:1}"); fi
        surface_chunks=("${chunks[@]+"${chunks[@]}"}")
    elif ! farm_fresh "$out/surface/manifest.json" "${inputs[@]}"; then
        run_merge=1
    fi
fi
if has_stage render; then
    inputs=("$out/$(has_stage surface && echo surface || echo sim)/manifest.json" "$out/render.params.json" "$bin/mc-render")
    if [ $run_sim -eq 1 ] || [ $run_merge -eq 1 ] || ! farm_fresh "$out/render/manifest.json" "${inputs[@]}"; then
        run_assemble=1
        missing=()
        if [ $run_sim -eq 1 ] || [ $run_merge -eq 1 ]; then
            mapfile -t missing < <(seq "$frame_first" "$frame_last")
        else
            for ((n = frame_first; n <= frame_last; n++)); do
                farm_fresh "$(farm_frame_file "$out/render" frame "$n" png)" "${inputs[@]}" || missing+=("$n")
            done
        fi
        mapfile -t render_chunks < <(printf '%s\n' "${missing[@]+"${missing[@]}"}" | sed '/^$/d' | farm_chunk_frames "$render_chunk")
    fi
fi

# -- submission -----------------------------------------------------------------------------------
name=$(basename "$out")
partition=${MUDCRACK_PARTITION:-${SLURM_PARTITION:-}}
account=${MUDCRACK_ACCOUNT:-${SLURM_ACCOUNT:-}}
# resources: the sim is one long multi-threaded job; per-frame tasks are short and single-core
declare -A defaults=(
    [INIT_CPUS]=2 [INIT_MEM]=4G [INIT_TIME]=01:00:00
    [SIM_CPUS]=2 [SIM_MEM]=8G [SIM_TIME]=2-00:00:00
    [SURFACE_CPUS]=1 [SURFACE_MEM]=4G [SURFACE_TIME]=02:00:00
    [MERGE_CPUS]=1 [MERGE_MEM]=1G [MERGE_TIME]=00:10:00
    [RENDER_CPUS]=2 [RENDER_MEM]=4G [RENDER_TIME]=02:00:00
    [ASSEMBLE_CPUS]=2 [ASSEMBLE_MEM]=4G [ASSEMBLE_TIME]=02:00:00
)
resource() {  # resource SIM CPUS -> $FARM_SIM_CPUS or the default
    local var=FARM_$1_$2
    echo "${!var:-${defaults[$1_$2]}}"
}

: >"$farm/jobs.tsv.new"
# task.sh wants KIND SHOT OUT BIN [extra]: the kind goes first, extras after the paths
submit_task() {  # submit_task CLASS TASK DEPENDENCY KIND [EXTRA...] [-- SBATCH_ARGS...]
    local class=$1 task=$2 dependency=$3 kind=$4
    shift 4
    local extra=() sb=()
    while [ $# -gt 0 ] && [ "$1" != -- ]; do extra+=("$1"); shift; done
    [ $# -gt 0 ] && { shift; sb=("$@"); }
    local wrap
    local args=(--parsable --job-name="mc-$name-$task" --kill-on-invalid-dep=yes
        --cpus-per-task="$(resource "$class" CPUS)" --mem="$(resource "$class" MEM)"
        --time="$(resource "$class" TIME)" --output="$out/logs/slurm/%x.%j.out")
    [ -n "$partition" ] && args+=(--partition="$partition")
    [ -n "$account" ] && args+=(--account="$account")
    [ -n "$dependency" ] && args+=(--dependency="$dependency")
    # shellcheck disable=SC2206
    [ -n "${FARM_SBATCH_ARGS:-}" ] && args+=(${FARM_SBATCH_ARGS})
    wrap=$(printf '%q ' bash "$FARM_DIR/task.sh" "$kind" "$shot" "$out" "$bin" "${extra[@]+"${extra[@]}"}")
    if [ $dry -eq 1 ]; then
        echo "DRY-$task"
        echo "would run: sbatch ${args[*]} ${sb[*]+"${sb[*]}"} --wrap '$wrap'" >&2
        return 0
    fi
    local id
    id=$(sbatch "${args[@]}" "${sb[@]+"${sb[@]}"}" --wrap "$wrap") || farm_die "sbatch failed for $task"
    echo "${id%%;*}"
}
record() {  # record STAGE JOB FRAMES TASK_NAME
    printf '%s\t%s\t%s\t%s\t%s\n' "$1" "$2" "$3" "$out/logs/$4.log" "$(date +%s.%N)" >>"$farm/jobs.tsv.new"
}
after() {  # after ID... -> "afterok:ID:ID" (empty without ids)
    local ids=("$@")
    [ ${#ids[@]} -gt 0 ] && (IFS=:; echo "afterok:${ids[*]}") || true
}

# one job array over a stage's frame chunks ("FIRST LAST" each), after the jobs in deps; each
# array task is recorded as its own row. Sets array_id (a $(...) call could not record).
submit_chunk_array() {  # submit_chunk_array STAGE CLASS CHUNK...
    local stage=$1 class=$2
    shift 2
    local chunks=("$@") i a b
    printf '%s\n' "${chunks[@]}" >"$farm/$stage.chunks"
    array_id=$(submit_task "$class" "$stage" "$(after "${deps[@]+"${deps[@]}"}")" "$stage-chunk" "$farm/$stage.chunks" \
        -- --array="1-${#chunks[@]}")
    for i in "${!chunks[@]}"; do
        read -r a b <<<"${chunks[$i]}"
        record "$stage" "${array_id}_$((i + 1))" "$a-$b" "$(farm_task_name "$stage" "$a" "$b")"
    done
}

deps=()
if [ $run_init -eq 1 ]; then
    id=$(submit_task INIT init "" init)
    record init "$id" - init
    deps=("$id")
fi
if [ $run_sim -eq 1 ]; then
    id=$(submit_task SIM sim "$(after "${deps[@]+"${deps[@]}"}")" \
        "$([ $resume -eq 1 ] && echo sim-resume || echo sim)")
    record sim "$id" "$frame_first-$frame_last" sim
    deps=("$id")
fi
if [ -n "$surface_prep" ]; then
    read -r a b <<<"$surface_prep"
    id=$(submit_task SURFACE "surface.$(farm_range_name "$a" "$b")" "$(after "${deps[@]+"${deps[@]}"}")" surface-prep "$a" "$b")
    record surface "$id" "$a-$b" "$(farm_task_name surface "$a" "$b")"
    deps=("$id")
fi
if [ ${#surface_chunks[@]} -gt 0 ]; then
    submit_chunk_array surface SURFACE "${surface_chunks[@]}"
    deps+=("$array_id")
fi
if [ $run_merge -eq 1 ]; then
    id=$(submit_task MERGE surface-merge "$(after "${deps[@]+"${deps[@]}"}")" surface-merge)
    record surface-merge "$id" - surface-merge
    deps=("$id")
fi
if [ ${#render_chunks[@]} -gt 0 ]; then
    submit_chunk_array render RENDER "${render_chunks[@]}"
    deps=("$array_id")
fi
if [ $run_assemble -eq 1 ]; then
    id=$(submit_task ASSEMBLE render-assemble "$(after "${deps[@]+"${deps[@]}"}")" render-assemble)
    record render-assemble "$id" - render-assemble
fi

if [ $dry -eq 1 ]; then
    cat "$farm/jobs.tsv.new"
    rm -f "$farm/jobs.tsv.new"
    exit 0
fi
mv "$farm/jobs.tsv.new" "$farm/jobs.tsv"
if [ ! -s "$farm/jobs.tsv" ]; then
    echo "mc-farm: $name: every stage is up to date; nothing submitted"
    rm -f "$farm/jobs.tsv"
    exit 0
fi
echo "mc-farm: $name: submitted $(wc -l <"$farm/jobs.tsv") tasks (logs in $out/logs/):"
awk -F'\t' '{ printf "  %-16s job %-10s frames %s\n", $1, $2, $3 }' "$farm/jobs.tsv"
if [ $wait -eq 0 ]; then
    echo "mc-farm: follow with: make farm-status SHOT=$name"
    exit 0
fi
# --wait: until every task left the queue, then the verdict
while [ -n "$(farm_in_queue "$farm/jobs.tsv")" ]; do sleep 0.5; done
exec bash "$FARM_DIR/status.sh" --out "$out" --check
