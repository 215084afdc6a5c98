#!/usr/bin/env bash
# Runs every fuzz target for SECONDS seconds each (default 3600), JOBS at a time (default 2), at
# the lowest priority, logging to fuzz/logs/<target>.log; crashes land in fuzz/artifacts/<target>/.
# Seeds the corpora from the repository's sample data first. Exits non-zero when any target
# fails to build, crashes, or leaves an artifact, naming it.
#   fuzz/run_all.sh 60        # the CI smoke run: one minute per target
set -u
cd "$(dirname "$0")"
SECONDS_EACH=${1:-3600}
JOBS=${JOBS:-2}
TARGETS=(parsers edit_script rig_assembly gltf_import fbx_import gltf_roundtrip cage_gen session_file)
DATA=../data
mkdir -p logs

# --- seed corpora (idempotent; corpus/ stays out of git) ---------------------------------------
seed() { mkdir -p "corpus/$1"; cp -n "$2" "corpus/$1/$3" 2>/dev/null || true; }
k=0
for f in "$DATA"/arm/arm.obj "$DATA"/arm/arm.skt "$DATA"/arm/arm.skw "$DATA"/arm/arm_cage_cageWeights.txt \
         "$DATA"/arm/arm_corWeights.txt "$DATA"/arm/arm_cage.maxvol "$DATA"/arm/arm_skelAnim.txt; do
  mkdir -p corpus/parsers
  { printf "\\x$(printf %02x "$k")"; head -c 3000 "$f"; } > "corpus/parsers/seed$k"
  k=$((k + 1))
done
# Reader 7: DQ blend weights (`<vertex> <b>` lines); reader 8: cage animation.
printf '\x07# b\n0 0.25\n2 1\n' > corpus/parsers/seed7
{ printf '\x08'; head -c 3000 "$DATA"/arm/arm_cageAnim.txt; } > corpus/parsers/seed8
# Files under 1 MB only: a multi-megabyte seed slows every mutation.
for f in "$DATA"/gltf/*/*.gl* "$DATA"/fox/Fox.glb; do
  [ "$(wc -c < "$f")" -lt 1000000 ] && seed gltf_import "$f" "$(basename "$f")"
done
# Skeletons hanging from other animated skeletons (crates/cagerig-formats/tests/
# gltf_nested_skeletons.rs writes it and checks it is current).
for f in seeds/gltf_import/*.gltf; do seed gltf_import "$f" "$(basename "$f")"; done
for f in "$DATA"/fbx/*.fbx; do seed fbx_import "$f" "$(basename "$f")"; done
mkdir -p corpus/rig_assembly
{ cat "$DATA"/fbx/blender_279_sausage_base_0.obj; printf '\0'; cat "$DATA"/arm/arm_cage.obj; } \
  > corpus/rig_assembly/sausage_in_arm_cage 2>/dev/null || true
mkdir -p corpus/edit_script
printf '%s' '{"steps":[{"op":"rotate_joint","joint":1,"axis":[0,0,1],"degrees":30},{"op":"move_posed_cage","vertices":[3],"offset":[0,0.1,0]}]}' \
  > corpus/edit_script/seed0

# Session files of the built-in bar written by this build (crates/cagerig-document/tests/
# fuzz_seeds.rs checks they are current): as opened, edited with keys, a skeleton draft, a studio
# binding, a file source.
for f in seeds/session_file/*.cagerig; do seed session_file "$f" "$(basename "$f")"; done

# --- build once, then run JOBS targets at a time --------------------------------------------------
if ! RUSTC_BOOTSTRAP=1 nice -n 19 cargo fuzz build -O -s none > logs/build.log 2>&1; then
  echo "fuzz: the targets failed to build (fuzz/logs/build.log):" >&2
  tail -20 logs/build.log >&2
  exit 1
fi
failed=()
run_one() {
  local t=$1
  mkdir -p "corpus/$t" "artifacts/$t"
  RUSTC_BOOTSTRAP=1 nice -n 19 cargo fuzz run -O -s none "$t" "corpus/$t" -- \
    -max_total_time="$SECONDS_EACH" -print_final_stats=1 -max_len=8192 -report_slow_units=30 \
    -artifact_prefix="artifacts/$t/" > "logs/$t.log" 2>&1
}
pids=()
names=()
for t in "${TARGETS[@]}"; do
  run_one "$t" &
  pids+=($!)
  names+=("$t")
  if [ "${#pids[@]}" -ge "$JOBS" ]; then
    wait "${pids[0]}" || failed+=("${names[0]}")
    pids=("${pids[@]:1}")
    names=("${names[@]:1}")
  fi
done
for i in "${!pids[@]}"; do
  wait "${pids[$i]}" || failed+=("${names[$i]}")
done
for t in "${TARGETS[@]}"; do
  runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "logs/$t.log" | grep -o '[0-9]*$' | tail -1)
  echo "fuzz $t: ${runs:-?} executions in ${SECONDS_EACH} s"
  # A slow unit (libFuzzer's slow-unit-* artifact: an input that took over 30 s, e.g. on a
  # loaded machine) is reported, not a failure; crashes, leaks, timeouts and OOMs are.
  for slow in artifacts/"$t"/slow-unit-*; do
    [ -e "$slow" ] && echo "fuzz $t: slow input kept in fuzz/$slow (not a failure)"
  done
  if [ -n "$(ls -A "artifacts/$t" 2>/dev/null | grep -v '^slow-unit-')" ]; then
    case " ${failed[*]-} " in *" $t "*) ;; *) failed+=("$t") ;; esac
  fi
done
if [ "${#failed[@]}" -gt 0 ]; then
  for t in "${failed[@]}"; do
    echo "fuzz: target $t FAILED (fuzz/logs/$t.log, fuzz/artifacts/$t/):" >&2
    grep -m1 -A12 -E 'panicked|ERROR: libFuzzer|deadly signal' "logs/$t.log" >&2 || tail -12 "logs/$t.log" >&2
  done
  exit 1
fi
echo "fuzz: every target ran ${SECONDS_EACH} s without a failure"
