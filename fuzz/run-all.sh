#!/usr/bin/env bash
# Runs every fuzz target in turn for SECONDS each (default 600: the issue's 10 minutes),
# each with a scratch corpus beside the committed seeds (corpus/<target>/ is read, not
# grown), 2 GB of memory and 10 s per input; prints each target's executions, new
# units and peak memory. A crash, hang or out-of-memory stops that target with its
# input in artifacts/<target>/ and makes this exit non-zero.
#
#   bash fuzz/run-all.sh [SECONDS] [TARGET...]       # needs nightly and cargo-fuzz
set -uo pipefail
cd "$(dirname "$0")"
SECONDS_EACH=${1:-600}
shift || true
TARGETS=("$@")
[ ${#TARGETS[@]} -gt 0 ] || TARGETS=(scene_json camera_json fileset gltf obj ply png bop nerf)
SCRATCH=${FUZZ_SCRATCH:-/tmp/localisebot-fuzz}
cargo +nightly fuzz build --release >/dev/null || exit 1
failed=0
for t in "${TARGETS[@]}"; do
  mkdir -p "$SCRATCH/corpus/$t"
  log="$SCRATCH/$t.log"
  start=$(date -u +%T)
  cargo +nightly fuzz run --release "$t" "$SCRATCH/corpus/$t" "corpus/$t" -- \
    -max_total_time="$SECONDS_EACH" -rss_limit_mb=2048 -timeout=10 -print_final_stats=1 >"$log" 2>&1
  rc=$?
  stat() { sed -n "s/^stat::$1: *//p" "$log"; }
  echo "$t: from $start, exit $rc, $(stat number_of_executed_units) executions, $(stat new_units_added) new units, peak $(stat peak_rss_mb) MB (log: $log)"
  [ $rc -eq 0 ] || failed=1
done
exit $failed
