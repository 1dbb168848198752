# shellcheck shell=bash
# Shared by submit.sh, status.sh and task.sh (sourced, not run). The farm keeps its own records in
# OUT/<shot>/farm/ and writes task logs to OUT/<shot>/logs/; the stage outputs are exactly those of
# a local run (pipeline/shot.mk), so a farm run and a local run can take over from each other.
#
# Layout of OUT/<shot>/farm/:
#   jobs.tsv                this submission: stage, job id, frames, log (one line per task)
#   jobs.<time>.tsv         earlier submissions
#   state/<task>            written by the task itself (key=value): job, frames, start, end, log,
#                           status = running | ok | failed | killed, rc
#   <stage>.chunks          the frame ranges of an array, one per line (line i = array index i):
#                           surface.chunks, render.chunks
#   surface-base/           the break history and manifest the surfacing chunks start from
#   surface-chunks/A-B.json the manifest each surfacing chunk wrote, merged at the end
#   work/<task>/            a chunk's private output root (inputs linked in), removed on success

farm_die() {
    echo "${FARM_PROGRAM:-farm}: $*" >&2
    exit 1
}

# "A-B" of a frame range, zero padded like the stage files (frame.0005.png)
farm_range_name() { printf '%04d-%04d' "$1" "$2"; }

# the task name a stage and frame range get in logs and state files: "surface.0005-0008", "sim"
farm_task_name() {
    if [ $# -ge 3 ]; then echo "$1.$(farm_range_name "$2" "$3")"; else echo "$1"; fi
}

# true when file $1 exists and is newer than every other argument that exists (make's rule;
# a missing prerequisite other than $1 is ignored here: the caller decides what must exist)
farm_fresh() {
    local target=$1
    shift
    [ -e "$target" ] || return 1
    local dep
    for dep in "$@"; do
        [ -e "$dep" ] || continue
        [ "$target" -nt "$dep" ] || return 1
    done
    return 0
}

# frame file name: <dir>/<stem>.####.<ext> (pipeline/io frame_path)
farm_frame_file() { printf '%s/%s.%04d.%s' "$1" "$2" "$3" "$4"; }

# Splits the frames given on stdin (one number per line, ascending) into chunks of at most $1
# frames of consecutive numbers; prints "first last" per chunk.
farm_chunk_frames() {
    awk -v size="$1" '
        function flush() { if (n > 0) print first, prev; n = 0 }
        { if (n > 0 && ($1 != prev + 1 || n >= size)) flush()
          if (n == 0) first = $1
          prev = $1; n++ }
        END { flush() }'
}

# One line per job (array task) of this user in the queue: "ID STATE REASON", e.g.
# "12_3 PENDING Dependency" (one squeue call, so status stays cheap with thousands of tasks).
# Fails when squeue cannot reach the controller.
farm_queue() { squeue -h -r -u "$(id -un)" -o '%i %T %r'; }

# the job ids of jobs file $1 (jobs.tsv) that are still queued or running, one per line
farm_in_queue() {
    local queue
    queue=$(farm_queue) || farm_die "squeue failed: is the Slurm controller reachable (SLURM_CONF)?"
    awk -F'\t' 'NR == FNR { split($0, q, " "); queued[q[1]] = 1; next } ($2 in queued) { print $2 }' \
        <(printf '%s\n' "$queue") "$1"
}
