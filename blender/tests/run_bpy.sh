#!/usr/bin/env bash
# The add-on's suite (run.sh) on current Blenders, headless, in PyPI's `bpy` module: one venv per
# version under target/bpy/<version> (kept while it holds that version), the bpy wheels and their
# dependencies downloaded once per machine into a wheel folder that later runs install from.
# For each version, Blender's own extension validator (what `blender --command extension
# validate` runs) checks the zip first, with Blender's list of valid tags.
# Usage: blender/tests/run_bpy.sh VERSION...   e.g. 4.2.23 4.5.15 5.0.1
# Environment: CAGERIG_BLENDER_ZIP (the add-on zip, built once for every version; built here when
# unset), CAGERIG_BPY_WHEELS (the wheel folder, default ~/.cache/cagerig/bpy-wheels).
# Needs python3 3.11 (the bpy modules are built for CPython 3.11).
set -euo pipefail
cd "$(dirname "$0")/../.."
[ $# -gt 0 ] || { echo "usage: $0 VERSION..." >&2; exit 2; }
if ! python3 -c 'import sys; sys.exit(sys.version_info[:2] != (3, 11))'; then
  echo "run_bpy.sh: PyPI's bpy modules need CPython 3.11, python3 is $(python3 --version)" >&2
  exit 1
fi
zip="${CAGERIG_BLENDER_ZIP:-$(blender/build_addon.sh)}"
wheels="${CAGERIG_BPY_WHEELS:-${XDG_CACHE_HOME:-$HOME/.cache}/cagerig/bpy-wheels}"
mkdir -p "$wheels"
failed=()
for v in "$@"; do
  t0=$SECONDS
  venv="target/bpy/$v"
  py="$venv/bin/python"
  if ! "$py" -c "import importlib.metadata as m, sys; sys.exit(m.version('bpy') != '$v')" 2>/dev/null; then
    rm -rf "$venv"
    python3 -m venv "$venv"
    if ! "$venv/bin/pip" install -q --no-index --find-links "$wheels" "bpy==$v" 2>/dev/null; then
      "$venv/bin/pip" download -q --only-binary :all: -d "$wheels" "bpy==$v"
      "$venv/bin/pip" install -q --no-index --find-links "$wheels" "bpy==$v"
    fi
  fi
  scripts=$(echo "$venv"/lib/python3.11/site-packages/bpy/*/scripts)
  echo "-- bpy $v: validate the extension package"
  "$py" "$scripts/addons_core/bl_pkg/cli/blender_ext.py" validate \
    --valid-tags "$scripts/modules/_bpy_internal/extensions/tags.py" "$zip" || { failed+=("$v (validate)"); continue; }
  echo "-- bpy $v: the add-on's suite"
  if CAGERIG_BLENDER_ZIP="$zip" CAGERIG_BLENDER_WORK="target/blender-tests/bpy-$v" BLENDER_PYTHON="$py" \
    blender/tests/run.sh | grep -E '^(Blender|FAIL|Error|Traceback|  File|[A-Za-z]*Error)|sync time'; then :; fi
  grep -q '^summary:' "target/blender-tests/bpy-$v/test.log" && ! grep -q '^FAIL' "target/blender-tests/bpy-$v/test.log" \
    || failed+=("$v")
  echo "-- bpy $v: $(sed '/^summary:/q' "target/blender-tests/bpy-$v/test.log" | grep -c '^ok' || true) checks passed, $((SECONDS - t0)) s"
done
if [ ${#failed[@]} -gt 0 ]; then
  echo "run_bpy.sh: failed on bpy ${failed[*]} (logs: target/blender-tests/bpy-<version>/test.log)" >&2
  exit 1
fi
