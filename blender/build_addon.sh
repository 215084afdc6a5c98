#!/usr/bin/env bash
# Builds the Blender add-on: the cagerig wheel (maturin, abi3, CPython >= 3.10) unpacked into
# cagerig_blender/vendor/, zipped with the add-on as target/cagerig_blender-<version>.zip.
# Usage: blender/build_addon.sh   (maturin on PATH, or in target/py-venv; cargo needed)
set -euo pipefail
cd "$(dirname "$0")/.."
version=$(sed -n 's/^version = "\(.*\)"/\1/p' Cargo.toml | head -n1)
manifest_version=$(sed -n 's/^version = "\(.*\)"/\1/p' blender/cagerig_blender/blender_manifest.toml)
if [ "$version" != "$manifest_version" ]; then
  echo "build_addon.sh: blender_manifest.toml says $manifest_version, Cargo.toml $version" >&2
  exit 1
fi
maturin=maturin
command -v maturin >/dev/null 2>&1 || maturin="$PWD/target/py-venv/bin/maturin"
wheels="target/blender-wheels"
rm -rf "$wheels" && mkdir -p "$wheels"
"$maturin" build --release -m crates/cagerig-py/Cargo.toml --out "$wheels" >&2
wheel=$(ls "$wheels"/cagerig-*.whl | head -n1)
stage="target/blender-addon"
rm -rf "$stage" && mkdir -p "$stage/cagerig_blender/vendor" "$stage/cagerig_blender/wheels"
cp blender/cagerig_blender/*.py blender/cagerig_blender/blender_manifest.toml "$stage/cagerig_blender/"
cp "$wheel" "$stage/cagerig_blender/wheels/"
printf 'wheels = ["./wheels/%s"]\n' "$(basename "$wheel")" >> "$stage/cagerig_blender/blender_manifest.toml"
out="target/cagerig_blender-$version.zip"
python3 - "$wheel" "$stage" "$out" <<'PY'
import os, sys, zipfile
wheel, stage, out = sys.argv[1:]
vendor = os.path.join(stage, "cagerig_blender", "vendor")
with zipfile.ZipFile(wheel) as w:
    for name in w.namelist():
        if name.startswith("cagerig/"):  # the package; not the .dist-info
            w.extract(name, vendor)
if not any(f.startswith("_cagerig") for f in os.listdir(os.path.join(vendor, "cagerig"))):
    sys.exit(f"build_addon.sh: no compiled module in {wheel}")
tmp = out + ".tmp"
with zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as z:
    for root, _dirs, files in os.walk(stage):
        for f in sorted(files):
            if f.endswith(".pyc"):
                continue
            path = os.path.join(root, f)
            z.write(path, os.path.relpath(path, stage))
os.replace(tmp, out)
PY
echo "$out"
