#!/usr/bin/env bash
# Runs the four fuzz targets side by side at the lowest priority for SECONDS seconds each
# (default 3600), logging to fuzz/logs/<target>.log; crashes land in fuzz/artifacts/<target>/.
set -u
cd "$(dirname "$0")"
SECONDS_EACH=${1:-3600}
mkdir -p logs
for t in parsers edit_script rig_assembly gltf_import; do
  mkdir -p "corpus/$t" "artifacts/$t"
  RUSTC_BOOTSTRAP=1 nice -n 19 cargo fuzz run -O -s none "$t" "corpus/$t" -- \
    -max_total_time="$SECONDS_EACH" -print_final_stats=1 -max_len=8192 \
    -artifact_prefix="artifacts/$t/" > "logs/$t.log" 2>&1 &
done
wait
