#!/usr/bin/env bash
# Re-makes the docs' pictures that depend on cages, edit scripts and the renderer (docs/images/),
# and prints the figures the pages state beside them. Run it from the repository root after the
# cage generator, CageUp, an edit script or the renderer changed, look at every picture, and
# update the figures the pages quote from what it prints.
#
#   tools/doc-pictures.sh            # pictures into docs/images/, figures on stdout
#   CAGERIG=path/to/cagerig tools/doc-pictures.sh
#
# Needs a graphics adapter (a software one works: lavapipe). The studio's and Blender's pictures
# are made by their own commands (docs/editor.md, blender/tests/); green-vs-mvc.png by
# `python examples/green_vs_mvc.py`.
set -euo pipefail
cd "$(dirname "$0")/.."
CAGERIG="${CAGERIG:-target/release/cagerig}"
if [ ! -x "$CAGERIG" ]; then
  cargo build --release -p cagerig-cli
fi
images=docs/images
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
fox=(data/fox/Fox.glb --cage data/fox/Fox_cage.obj)
figure() { printf '%-58s %s\n' "$1" "$2"; }

# README: the demo strip.
"$CAGERIG" demo --out "$work/demo" >/dev/null 2>&1
cp "$work/demo/sequence.png" "$images/demo-sequence.png"

# README: the Arm after its edit script (grabbed cage vertices marked).
"$CAGERIG" render data/arm/arm.obj --script examples/arm-edits.json --view both --camera front \
  --out "$images/arm-edited.png" >/dev/null 2>&1

# README, characters.md: the Fox as loaded, and after its edit script.
"$CAGERIG" render "${fox[@]}" --size 900x600 --out "$images/fox.png" >/dev/null 2>&1
"$CAGERIG" render "${fox[@]}" --script examples/fox-edits.json --view both --camera side \
  --size 1400x620 --out "$images/fox-edited.png" >/dev/null 2>&1

# README: the current cage with the paper's CageUp and the default, and how far C' strays
# (worst over the Run sampled every 0.05 s).
run_times=$(python3 -c 'print(",".join(f"{0.05 * k:.2f}" for k in range(24)))')
for fit in paper regularised; do
  "$CAGERIG" render "${fox[@]}" --animation Run --times 0.4 --view current --camera side \
    --size 800x560 --cage-fit "$fit" --out "$images/fox-run-cage-$fit.png" >/dev/null 2>&1
  reach=$("$CAGERIG" animate "${fox[@]}" --animation Run --times "$run_times" \
    --cage-fit "$fit" --json --out "$work/run-$fit" 2>/dev/null \
    | python3 -c 'import json,sys; print(round(json.load(sys.stdin)["worst"]["spread"], 2))')
  figure "README: Fox Run, C' spread over the rest cage's (--cage-fit $fit)" "${reach}x"
done

# README, weights.md: the Fox's artist and computed weights of a hind leg.
weights=(--color-by joint:b_LeftLeg01_015 --view rest --show mesh,skeleton --camera side --size 640x400)
"$CAGERIG" render "${fox[@]}" "${weights[@]}" --out "$images/fox-weights-artist.png" >/dev/null 2>&1
"$CAGERIG" render "${fox[@]}" --auto-weights "${weights[@]}" --out "$images/fox-weights-auto.png" >/dev/null 2>&1

# README, characters.md: a generated 58-vertex cage on the Arm, and its validator's figures.
"$CAGERIG" cage data/arm/arm.obj --vertices 58 --out "$work/arm-cage58.obj" --json >"$work/cage58.json"
"$CAGERIG" render data/arm/arm.obj --cage "$work/arm-cage58.obj" --camera front \
  --show mesh,cage,ground --out "$images/arm-generated-cage.png" >/dev/null 2>&1
cage_figures() {
  python3 -c '
import json, sys
r = json.load(open(sys.argv[1]))["cage"]
print("least %.2f %% / mean %.2f %% of the diagonal, MaxVol condition %.3g"
      % (100 * r["min_distance_fraction"], 100 * r["mean_distance_fraction"], r["maxvol_condition"]))' "$1"
}
figure "characters.md: Arm, generated 58-vertex cage" "$(cage_figures "$work/cage58.json")"
for rig in "data/arm/arm.obj" "--builtin bar" "--builtin snake" "data/fox/Fox.glb"; do
  # shellcheck disable=SC2086
  "$CAGERIG" cage $rig --json >"$work/cage.json"
  figure "characters.md: default cage (100 vertices), $rig" "$(cage_figures "$work/cage.json")"
done
echo "pictures written to $images/"
