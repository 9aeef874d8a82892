#!/usr/bin/env bash
# Layer stacks on the truth scenes (issue 33): each scene's single-layer passes, the hand-made
# merge (each view layer blurred alone, `oiiotool --over`), and `--layers FG,BG`, scored as
# `shutter bench` scores (region RMSE against the brute-force reference, the region being
# the pixels the reference changes). Opt-in, not run by CI; needs oiiotool.
#
#   scripts/layers/truth.sh
#
# Environment: OUT (default target/layers/truth), SIZE (320x180), SAMPLES (256), SCENES
# (rotor crossing pan gears orbit layers), ALGS (reconstruct scatter stretch), DOF (1: also
# `shutter dof` gather and blend on `layers`), SHUTTER_BIN (default: cargo build --release).
set -euo pipefail

here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
cd "$root"
OUT=${OUT:-target/layers/truth}
SIZE=${SIZE:-320x180}
SAMPLES=${SAMPLES:-256}
SCENES=${SCENES:-rotor crossing pan gears orbit layers}
ALGS=${ALGS:-reconstruct scatter stretch}
DOF=${DOF:-1}
if [ -n "${SHUTTER_BIN:-}" ]; then
  S=$SHUTTER_BIN
else
  cargo build --release
  S=target/release/shutter
fi
command -v oiiotool >/dev/null || { echo "truth.sh: needs oiiotool (openimageio-tools)" >&2; exit 1; }

rgba() { echo "R=$1.Combined.R,G=$1.Combined.G,B=$1.Combined.B,A=$1.Combined.A"; }
# region REFERENCE CANDIDATE: region RMSE (the bench's score).
region() {
  "$S" diff "$1" "$2" --sharp color.0001.exr --json -q 2>/dev/null |
    python3 -c 'import json,sys; print("%.5f" % json.load(sys.stdin)["frames"][0]["region"]["rmse"])'
}
# row LABEL REFERENCE BLUR...: single layer, hand-made merge, stack, for one command line.
row() {
  local label=$1 reference=$2 tag=$3
  shift 3
  "$S" "$@" -q --color color.0001.exr --depth depth.0001.exr --velocity velocity.0001.exr \
    --prev prev.0001.exr --next next.0001.exr -o "single_$tag.exr" 2>/dev/null ||
    "$S" "$@" -q --color color.0001.exr --depth depth.0001.exr -o "single_$tag.exr"
  for layer in FG BG; do
    "$S" "$@" -q --preset blender --layer "$layer" --beauty-only --color layers.0001.exr \
      -o "${layer}_$tag.exr"
  done
  oiiotool "FG_$tag.exr" --ch "$(rgba FG)" "BG_$tag.exr" --ch "$(rgba BG)" --over \
    -o "merged_$tag.exr"
  "$S" "$@" -q --preset blender --layers FG,BG --beauty-only --color layers.0001.exr \
    -o "stack_$tag.exr"
  echo "| $label | $(region "$reference" "single_$tag.exr") | $(region "$reference" \
    "merged_$tag.exr") | $(region "$reference" "stack_$tag.exr") |"
}

echo "| scene, algorithm | single layer | hand-made merge | --layers FG,BG |"
echo "|---|---|---|---|"
for scene in $SCENES; do
  dir=$OUT/$scene
  [ -f "$dir/layers.0001.exr" ] ||
    "$S" scene "$scene" --layers --size "$SIZE" --samples "$SAMPLES" -o "$dir" 2>/dev/null
  (
    cd "$dir"
    for alg in $ALGS; do
      row "$scene, $alg" reference.0001.exr "$alg" blur --algorithm "$alg"
    done
    if [ "$DOF" = 1 ] && [ -f reference_dof.0001.exr ]; then
      for method in gather blend; do
        row "$scene dof, $method" reference_dof.0001.exr "dof_$method" dof --method "$method" \
          --focal-length 50 --f-stop 1.4 --focus-distance 3 --sensor-width 36
      done
    fi
  )
done
