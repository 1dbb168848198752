#!/usr/bin/env bash
# One unit of chunked stage work: a farm task run by Slurm on a compute node (submit.sh submits
# it), or a job of a parallel local make (pipeline/shot.mk runs the chunks of `make -jN shot`).
#
#   task.sh KIND SHOT_FILE SHOT_OUT BIN [FIRST LAST | CHUNKS_FILE]
#
# KIND: init | sim | sim-resume | surface-prep FIRST LAST | surface-chunk FIRST LAST|CHUNKS_FILE |
#       surface-merge | render-chunk FIRST LAST|CHUNKS_FILE | render-assemble | render (all of it)
# A Slurm array task (surface-chunk, render-chunk) given CHUNKS_FILE takes its frames from line
# $SLURM_ARRAY_TASK_ID of it; given FIRST LAST (make) it runs those frames.
# The task appends to its log OUT/logs/<task>.log and writes its state to OUT/farm/state/<task>
# (status=running, then ok / failed / killed), which status.sh reads once the job left the queue.
# Stage outputs land exactly where a local run puts them; per-chunk work happens in a private
# folder and only finished files are renamed into place, so a killed task leaves no partial file.
set -uo pipefail

FARM_PROGRAM=mc-farm-task
FARM_DIR=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
# shellcheck source=farm_lib.sh
. "$FARM_DIR/farm_lib.sh"

[ $# -ge 4 ] || farm_die "usage: task.sh KIND SHOT_FILE SHOT_OUT BIN [FIRST LAST | CHUNKS_FILE]"
kind=$1 shot=$2 out=$3 bin=$4
shift 4
# absolute paths: the chunk work folders link the shot's init/ and sim/ by path
[ -f "$shot" ] || farm_die "$shot: no such shot file"
[ -d "$bin" ] || farm_die "$bin: no such folder (the stage binaries)"
mkdir -p "$out" || farm_die "$out: cannot create"
shot=$(cd "$(dirname "$shot")" && pwd)/$(basename "$shot") out=$(cd "$out" && pwd) bin=$(cd "$bin" && pwd)

first="" last=""
case $kind in
    surface-prep) first=$1 last=$2 ;;
    surface-chunk | render-chunk)
        if [ $# -ge 2 ]; then
            first=$1 last=$2
        else
            [ -n "${SLURM_ARRAY_TASK_ID:-}" ] || farm_die "$kind CHUNKS_FILE runs as a Slurm array task (or give FIRST LAST)"
            read -r first last < <(sed -n "${SLURM_ARRAY_TASK_ID}p" "$1")
            [ -n "$first" ] || farm_die "$1: no line $SLURM_ARRAY_TASK_ID"
        fi
        ;;
esac
[ -z "$first" ] || [[ $first =~ ^[0-9]+$ && $last =~ ^[0-9]+$ && $first -le $last ]] ||
    farm_die "$kind: frames '$first' '$last': expected FIRST <= LAST, whole numbers"
# the task's name in logs and state files: "init", "sim", "surface.0005-0008", "surface-merge",
# "render.0005-0008", "render-assemble"
if [ -n "$first" ]; then
    name=$(farm_task_name "${kind%%-*}" "$first" "$last")
elif [ "$kind" = sim-resume ]; then
    name=sim
else
    name=$kind
fi
if [ -n "${SLURM_ARRAY_JOB_ID:-}" ]; then job=${SLURM_ARRAY_JOB_ID}_${SLURM_ARRAY_TASK_ID}; else job=${SLURM_JOB_ID:-local}; fi

mkdir -p "$out/logs" "$out/farm/state"
log=$out/logs/$name.log
state=$out/farm/state/$name
# everything goes to the task's log; fd 3 keeps the caller's stderr for the verdict on failure
exec 3>&2 >>"$log" 2>&1
# FARM_THREADS (make: the job's share of the cores) wins over the CPUs Slurm allocated
threads=${FARM_THREADS:-${SLURM_CPUS_PER_TASK:-$(nproc)}}
start=$(date +%s.%N)
echo "=== $name: job $job on $(hostname -s), $threads threads, $(date -Is)"

# state=key=value lines, rewritten atomically
write_state() {
    local status=$1 rc=${2:-}
    {
        echo "job=$job"
        echo "frames=${first:+$first-$last}"
        echo "host=$(hostname -s)"
        echo "start=$start"
        echo "status=$status"
        [ -n "$rc" ] && echo "rc=$rc"
        [ "$status" != running ] && echo "end=$(date +%s.%N)"
        echo "log=$log"
    } >"$state.tmp" && mv -f "$state.tmp" "$state"
}

# scancel (or the time limit) sends SIGTERM: pass it to the stage and record the task as killed
child=""
on_term() {
    [ -n "$child" ] && kill -TERM "$child" 2>/dev/null
    [ -n "$child" ] && wait "$child" 2>/dev/null
    echo "=== $name: killed (SIGTERM) at $(date -Is)"
    write_state killed 143
    echo "$FARM_PROGRAM: $name${first:+ (frames $first-$last)} killed; log $log" >&3
    exit 143
}
trap on_term TERM INT
write_state running

# runs a command in the background so the TERM trap fires at once; returns its exit code
run() {
    echo "+ $*"
    "$@" &
    child=$!
    wait "$child"
    local rc=$?
    child=""
    return $rc
}

flags=(--shot "$shot" --out "$out" --threads "$threads")

# mc-surface on frames first..last in a private output root whose init/ and sim/ are the shot's;
# an existing base (break history + manifest) makes mc-surface update it in place rather than
# rescan every frame. Then the frame files are renamed into OUT/surface/, crack before boundary
# (submit.sh takes a fresh boundary file to mean the frame is done).
surface_frames() {
    local work=$out/farm/work/$name base=$out/farm/surface-base
    rm -rf "$work" && mkdir -p "$work/surface" || return 1
    ln -s "$out/init" "$work/init" && ln -s "$out/sim" "$work/sim" || return 1
    if [ "$kind" = surface-chunk ]; then
        cp "$base/manifest.json" "$base/edge_breaks.bin" "$work/surface/" || return 1
    else
        rmdir "$work/surface"  # the first chunk builds the stage folder from scratch
    fi
    run "$bin/mc-surface" --shot "$shot" --out "$work" --frames "$first-$last" \
        --threads "$threads" || return $?
    local format
    format=$(jq -r .format "$work/surface/manifest.json") || return 1
    mkdir -p "$out/farm/surface-chunks" || return 1
    cp "$work/surface/manifest.json" "$out/farm/surface-chunks/.$name.tmp" &&
        mv -f "$out/farm/surface-chunks/.$name.tmp" "$out/farm/surface-chunks/$(farm_range_name "$first" "$last").json" ||
        return 1
    if [ "$kind" = surface-prep ]; then
        # a new base: every chunk of an earlier base is void, and so are the old stage files
        rm -rf "$base.tmp" && mkdir -p "$base.tmp" &&
            cp "$work/surface/manifest.json" "$work/surface/edge_breaks.bin" "$base.tmp/" &&
            rm -rf "$base" && mv "$base.tmp" "$base" || return 1
        find "$out/farm/surface-chunks" -name '*.json' ! -name "$(farm_range_name "$first" "$last").json" -delete
        rm -rf "$out/surface" && mkdir -p "$out/surface" || return 1
    fi
    mkdir -p "$out/surface" || return 1
    local n
    for ((n = first; n <= last; n++)); do
        local crack boundary debris
        crack=$(farm_frame_file "$work/surface" crack "$n" "$format")
        boundary=$(farm_frame_file "$work/surface" boundary "$n" "$format")
        debris=$(farm_frame_file "$work/surface" debris "$n" ply)  # the plates mode's, on request
        rm -f "$(farm_frame_file "$out/surface" crack "$n" "$format")" "$(farm_frame_file "$out/surface" debris "$n" ply)"
        if [ -f "$crack" ]; then mv -f "$crack" "$out/surface/" || return 1; fi
        if [ -f "$debris" ]; then mv -f "$debris" "$out/surface/" || return 1; fi
        mv -f "$boundary" "$out/surface/" || return 1
    done
    rm -rf "$work"
}

# OUT/surface/manifest.json from the base and every chunk's manifest (each chunk contributes the
# frames it ran), written last and atomically, like a local mc-surface run. Fails naming any
# frame without a mesh or a manifest entry, and any file whose bytes are not those its chunk
# recorded (mc-shot verify: "damaged").
surface_merge() {
    local base=$out/farm/surface-base first_frame last_frame
    first_frame=$(jq -r .frames.first "$out/sim/manifest.json") &&
        last_frame=$(jq -r .frames.last "$out/sim/manifest.json") || return 1
    local chunks=()
    mapfile -t chunks < <(ls -tr "$out"/farm/surface-chunks/*.json 2>/dev/null)
    [ ${#chunks[@]} -gt 0 ] || { echo "no chunk manifests in $out/farm/surface-chunks"; return 1; }
    echo "+ merging ${#chunks[@]} chunk manifests of frames $first_frame-$last_frame"
    local merged=$out/surface/.manifest.json.farm.tmp
    jq -s --argjson first "$first_frame" --argjson last "$last_frame" --argjson chunks ${#chunks[@]} '
        .[0] as $base
        | (reduce (.[1:][] | .frames.this_run as $run | .per_frame[]
                   | select(.frame >= $run.first and .frame <= $run.last)) as $e
              ({}; .[$e.frame | tostring] = $e)) as $by_frame
        | [range($first; $last + 1) | tostring | select($by_frame[.] == null)] as $missing
        | if ($missing | length) > 0 then error("frames without a surfacing entry: \($missing | join(" "))")
          else . end
        | [range($first; $last + 1) | $by_frame[tostring]] as $per_frame
        | $base
        | .frames = {first: $first, last: $last, count: ($last - $first + 1), fps: $base.frames.fps,
                     this_run: {first: $first, last: $last}}
        | .per_frame = $per_frame
        | .surfacing_seconds = ([$per_frame[].surfacing_seconds // 0] | add)
        | .farm = {chunks: $chunks}' \
        "$base/manifest.json" "${chunks[@]}" >"$merged" || { rm -f "$merged"; return 1; }
    local format n missing=""
    format=$(jq -r .format "$merged")
    for ((n = first_frame; n <= last_frame; n++)); do
        [ -f "$(farm_frame_file "$out/surface" boundary "$n" "$format")" ] || missing="$missing $n"
    done
    [ -z "$missing" ] || { rm -f "$merged"; echo "frames without a boundary mesh:$missing"; return 1; }
    # every file the chunks moved in, and the history, checked against the checksums their
    # manifests recorded before the manifest that vouches for them is moved into place
    cp "$base/edge_breaks.bin" "$out/surface/.edge_breaks.bin.farm.tmp" &&
        mv -f "$out/surface/.edge_breaks.bin.farm.tmp" "$out/surface/edge_breaks.bin" &&
        "$bin/mc-shot" verify "$merged" &&
        mv -f "$merged" "$out/surface/manifest.json" || { rm -f "$merged"; return 1; }
}

case $kind in
    init) run "$bin/mc-init" "${flags[@]}" ;;
    sim) run "$bin/mc-sim" "${flags[@]}" ;;
    sim-resume) run "$bin/mc-sim" "${flags[@]}" --resume ;;
    surface-prep | surface-chunk) surface_frames ;;
    surface-merge) surface_merge ;;
    # the frames of a chunk, each PNG renamed into OUT/render/ when complete (mc-render --frames)
    render-chunk) run "$bin/mc-render" "${flags[@]}" --frames "$first-$last" ;;
    render-assemble) run "$bin/mc-render" "${flags[@]}" --assemble ;;
    render) run "$bin/mc-render" "${flags[@]}" ;;
    *) farm_die "unknown task kind '$kind'" ;;
esac
rc=$?
if [ $rc -eq 0 ]; then
    write_state ok 0
    echo "=== $name: ok in $(awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN { printf "%.2f", b - a }') s"
else
    write_state failed $rc
    echo "=== $name: FAILED (exit $rc)"
    {
        echo "$FARM_PROGRAM: $name${first:+ (frames $first-$last)} FAILED (exit $rc); log $log ends with:"
        tail -n 12 "$log" | sed 's/^/    /'
    } >&3
fi
exit $rc
