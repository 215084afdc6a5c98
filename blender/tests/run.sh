#!/usr/bin/env bash
# Headless tests of the Blender add-on: builds the add-on zip, exports the Arm as
# glTF, then runs test_addon.py inside Blender (install the zip, enable, couple, the three
# interactions against Blender's own evaluation, save/reopen, undo, bake, errors, and the same
# edits through the cagerig Python package).
# Usage: blender/tests/run.sh   (needs blender, python3-numpy for Blender's Python, cargo, maturin)
set -euo pipefail
cd "$(dirname "$0")/../.."
BLENDER="${BLENDER:-blender}"
work="${CAGERIG_BLENDER_WORK:-target/blender-tests}"
rm -rf "$work" && mkdir -p "$work"
work="$(cd "$work" && pwd)"
zip="${CAGERIG_BLENDER_ZIP:-$(blender/build_addon.sh)}"
cli="${CAGERIG_CLI:-target/release/cagerig}"
[ -x "$cli" ] || cargo build --release -q -p cagerig-cli
"$cli" export data/arm/arm.obj --out "$work/arm.glb" >/dev/null 2>&1
# A private user-scripts folder: the add-on is installed there, not into ~/.config.
export BLENDER_USER_SCRIPTS="$work/user-scripts"
export BLENDER_USER_CONFIG="$work/user-config"
"$BLENDER" -b --factory-startup --python-exit-code 1 --python blender/tests/test_addon.py -- \
  "$(cd "$(dirname "$zip")" && pwd)/$(basename "$zip")" "$work/arm.glb" "$PWD/data/arm/arm_cage.obj" "$work" \
  2>&1 | tee "$work/test.log" | grep -E '^(ok|FAIL|skip|Error|Traceback|  File|[A-Za-z]*Error)' || true
grep -q '^summary:' "$work/test.log" && ! grep -q '^FAIL' "$work/test.log"
