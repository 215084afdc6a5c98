#!/usr/bin/env bash
# Headless tests of the Blender add-on: builds the add-on zip, exports the Arm as
# glTF, then runs test_addon.py inside Blender (install the zip, enable, couple, the three
# interactions against Blender's own evaluation, save/reopen, undo, bake, errors, the same
# edits through the cagerig Python package, every rig option, and the automatic weights on the
# Arm and data/fox/Fox.glb against Blender's bone heat).
# Usage: blender/tests/run.sh   (needs blender, python3-numpy for Blender's Python, cargo, maturin)
# Environment: BLENDER (the binary, default `blender`) or BLENDER_PYTHON (a Python with PyPI's
# `bpy` module, which then runs the test as a script); CAGERIG_BLENDER_ZIP (an add-on zip already
# built: no build); CAGERIG_BLENDER_WORK (the work folder, default target/blender-tests).
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
# Private user folders: the add-on is installed there, not into ~/.config.
export BLENDER_USER_SCRIPTS="$work/user-scripts"
export BLENDER_USER_CONFIG="$work/user-config"
export BLENDER_USER_EXTENSIONS="$work/user-extensions"
args=("$(cd "$(dirname "$zip")" && pwd)/$(basename "$zip")" "$work/arm.glb" "$PWD/data/arm/arm_cage.obj" "$work" "$PWD/data/fox/Fox.glb")
if [ -n "${BLENDER_PYTHON:-}" ]; then
  cmd=("$BLENDER_PYTHON" blender/tests/test_addon.py -- "${args[@]}")
else
  cmd=("$BLENDER" -b --factory-startup --python-exit-code 1 --python blender/tests/test_addon.py -- "${args[@]}")
fi
status=0
"${cmd[@]}" >"$work/test.log" 2>&1 || status=$?
grep -E '^(ok|FAIL|skip|Blender|Error|Traceback|  File|[A-Za-z]*Error)' "$work/test.log" || true
[ "$status" -eq 0 ] && grep -q '^summary:' "$work/test.log" && ! grep -q '^FAIL' "$work/test.log"
