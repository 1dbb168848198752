#!/usr/bin/env bash
# What the last farm submission of a shot is doing: one line per task (stage, frames, job id,
# state, wait and run time, log), then the counts. A task is queued or running while squeue lists
# it; after that its own state file (written by task.sh) says done, failed or killed; a task that
# left the queue without a state file never started (cancelled, or its dependency failed).
# Slurm accounting (sacct) is not needed.
#
#   status.sh --out out/demo [--failures-only] [--check]
#
# --failures-only  print only the failed, killed and never-run tasks (submit.sh uses it)
# --check          exit 0 when every task is done, 3 while some are queued or running, 1 otherwise
set -euo pipefail

FARM_PROGRAM=mc-farm-status
FARM_DIR=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
# shellcheck source=farm_lib.sh
. "$FARM_DIR/farm_lib.sh"

out="" failures_only=0 check=0
while [ $# -gt 0 ]; do
    case $1 in
        --out) out=$2; shift 2 ;;
        --failures-only) failures_only=1; shift ;;
        --check) check=1; shift ;;
        *) echo "usage: status.sh --out OUT/<shot> [--failures-only] [--check]" >&2; exit 2 ;;
    esac
done
[ -n "$out" ] || { echo "usage: status.sh --out OUT/<shot> [--failures-only] [--check]" >&2; exit 2; }
jobs=$out/farm/jobs.tsv
if [ ! -f "$jobs" ]; then
    [ $failures_only -eq 1 ] || echo "mc-farm: no farm submission recorded in $out/farm/ (run: make shot SHOT=$(basename "$out") FARM=slurm)"
    exit 0
fi
queue=$(farm_queue 2>/dev/null) || { queue=""; echo "mc-farm: warning: squeue failed (controller unreachable?): queue states unknown" >&2; }

# value of key $2 in state file $1
state_value() { sed -n "s/^$2=//p" "$1" 2>/dev/null | head -n 1; }
seconds() { awk -v a="$1" -v b="$2" 'BEGIN { if (a == "" || b == "") print "-"; else printf "%.1f", b - a }'; }

queued=0 running=0 finished=0 failed=0 never=0
[ $failures_only -eq 1 ] || printf '%-16s %-10s %-12s %-24s %8s %8s  %s\n' stage frames job state "wait[s]" "run[s]" log
while IFS=$'\t' read -r stage job frames log submitted; do
    task=$(basename "$log" .log)
    state_file=$out/farm/state/$task
    line=$(awk -v id="$job" '$1 == id { print; exit }' <<<"$queue")
    wait_s="-" run_s="-"
    # a state file counts only if this very job wrote it (not an earlier submission's task)
    [ -f "$state_file" ] && [ "$(state_value "$state_file" job)" = "$job" ] || state_file=""
    if [ -n "$state_file" ]; then
        start=$(state_value "$state_file" start)
        wait_s=$(seconds "$submitted" "$start")
        run_s=$(seconds "$start" "$(state_value "$state_file" end)")
    fi
    if [ -n "$line" ]; then
        read -r _ qstate reason <<<"$line"
        case $qstate in
            PENDING) state="queued ($reason)"; queued=$((queued + 1)) ;;
            *) state=$(tr '[:upper:]' '[:lower:]' <<<"$qstate"); running=$((running + 1)) ;;
        esac
    elif [ -z "$state_file" ]; then
        state="not run (cancelled)"; never=$((never + 1))
    else
        case $(state_value "$state_file" status) in
            ok) state="done"; finished=$((finished + 1)) ;;
            killed) state="KILLED"; failed=$((failed + 1)) ;;
            failed) state="FAILED (exit $(state_value "$state_file" rc))"; failed=$((failed + 1)) ;;
            *) state="LOST (ended without status)"; failed=$((failed + 1)) ;;
        esac
    fi
    if [ $failures_only -eq 1 ]; then
        case $state in
            KILLED* | FAILED* | LOST* | "not run"*)
                echo "mc-farm: last submission: $stage frames $frames (job $job): $state; log $log" ;;
        esac
    else
        printf '%-16s %-10s %-12s %-24s %8s %8s  %s\n' "$stage" "$frames" "$job" "$state" "$wait_s" "$run_s" "$log"
    fi
done <"$jobs"
[ $failures_only -eq 1 ] || echo "queued $queued, running $running, done $finished, failed $failed, not run $never"
if [ $check -eq 1 ]; then
    [ $((queued + running)) -eq 0 ] || exit 3
    [ $((failed + never)) -eq 0 ] || exit 1
fi
exit 0
