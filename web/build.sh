#!/bin/sh
# Builds the web studio into target/web/: index.html, the wasm and its JS glue, and the sample
# characters (the Arm as a .glb with its hand-made cage, the Fox, CesiumMan).
# Needs the wasm32-unknown-unknown target (rustup) and the wasm-bindgen command of the same
# version as the crate's wasm-bindgen (both installed here when missing).
# Serve it with:  python3 -m http.server --bind 127.0.0.1 --directory target/web 8080
set -eu
cd "$(dirname "$0")/.."
out=target/web
bindgen_version=0.2.130

if command -v rustup >/dev/null 2>&1 && ! rustup target list --installed | grep -qx wasm32-unknown-unknown; then
    rustup target add wasm32-unknown-unknown
fi
if ! wasm-bindgen --version 2>/dev/null | grep -q " $bindgen_version\$"; then
    cargo install wasm-bindgen-cli --version "$bindgen_version"
fi

# 128-bit SIMD (every current browser has it): LLVM vectorises the f64 kernels two lanes wide.
# The flags are the web target's only, so native builds keep theirs.
CARGO_TARGET_WASM32_UNKNOWN_UNKNOWN_RUSTFLAGS="-C target-feature=+simd128" \
    cargo build --profile web --target wasm32-unknown-unknown -p cagerig-web
# The Arm's OBJ file set becomes one .glb with its cage node (the CLI of this repository).
cargo build --release -p cagerig-cli

staging=$(mktemp -d "${TMPDIR:-/tmp}/cagerig-web.XXXXXX")
trap 'rm -rf "$staging"' EXIT
wasm-bindgen --target web --no-typescript --out-dir "$staging" \
    target/wasm32-unknown-unknown/web/cagerig_web.wasm
cp web/index.html web/worker.js "$staging/"
mkdir "$staging/samples"
target/release/cagerig export data/arm/arm.obj --out "$staging/samples/Arm.glb" >/dev/null
cp data/fox/Fox.glb data/gltf/CesiumMan/CesiumMan.glb "$staging/samples/"
cp data/arm/LICENSE "$staging/samples/Arm.LICENSE"
cp data/gltf/README.md "$staging/samples/CesiumMan.README.md"
cp data/fox/README.md "$staging/samples/Fox.README.md"
chmod -R a+rX "$staging"
rm -rf "$out"
mv "$staging" "$out"
trap - EXIT
echo "web studio written to $out ($(du -sh "$out" | cut -f1)):"
ls -l "$out" "$out/samples"
