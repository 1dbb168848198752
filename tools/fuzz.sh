#!/usr/bin/env bash
# make fuzz: runs every libFuzzer target of BUILD_FUZZ (listed in its fuzz_targets.txt as
# "name binary regression-folder seed...") for SECONDS each, nice'd. Each target's working corpus
# is BUILD_FUZZ/corpus/<name>, seeded from the repo's seeds and regressions; an input that crashes,
# hangs (-timeout) or trips a sanitizer is kept as BUILD_FUZZ/findings/<name>/ and the run fails:
# fix the reader and copy the input into tests/fuzz/regressions/<name>/.
# usage: tools/fuzz.sh BUILD_FUZZ SECONDS
set -euo pipefail
build=$1 seconds=$2
list=$build/fuzz_targets.txt
[[ -f $list ]] || { echo "fuzz: $list: missing (configure $build with MUDCRACK_FUZZ=ON)"; exit 2; }
# assimp's own leaks on malformed files are suppressed (tests/fuzz/lsan.supp says why)
export LSAN_OPTIONS="suppressions=$(cd "$(dirname "$0")/.." && pwd)/tests/fuzz/lsan.supp${LSAN_OPTIONS:+:$LSAN_OPTIONS}"
failed=()
while read -r name bin regressions seeds; do
  [[ -n $name ]] || continue
  corpus=$build/corpus/$name findings=$build/findings/$name
  mkdir -p "$corpus" "$findings"
  for s in $regressions $seeds; do
    if [[ -d $s ]]; then cp -n "$s"/* "$corpus"/ 2>/dev/null || true; elif [[ -f $s ]]; then cp -n "$s" "$corpus"/; fi
  done
  log=$build/fuzz_$name.log
  echo "fuzz: $name for ${seconds} s (log $log)"
  # -timeout: one input taking over 10 s is a hang; -rss_limit_mb: a hostile size that makes a
  # reader allocate gigabytes is a finding too
  if nice -n 10 "$bin" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
       -artifact_prefix="$findings/" "$corpus" > "$log" 2>&1; then
    runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo '?')
    echo "fuzz: $name: $runs inputs, no finding"
  else
    echo "fuzz: $name: FINDING (see $log and $findings/)"
    failed+=("$name")
  fi
done < "$list"
if ((${#failed[@]})); then echo "fuzz: findings in: ${failed[*]}"; exit 1; fi
echo "fuzz: every target clean"
