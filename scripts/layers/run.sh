#!/usr/bin/env bash
# A real Cycles render with view layers (issue 33), and shutter's error on it against Cycles'
# own motion blur and depth of field. Opt-in, not run by CI: it downloads bpy (about 400 MB)
# into target/peers/venv, as scripts/peers/run.sh does. See README.md beside this file.
#
#   scripts/layers/run.sh
#   SCENE=gear-spin scripts/layers/run.sh     # or gear-slide: the gear, README.md
#
# Environment: SCENE (fan, gear-spin or gear-slide: scene.py's --scene; default fan), OUT
# (default target/layers/real for the fan, target/layers/real-SCENE for a gear), SIZE
# (480x270), SAMPLES (128, the sharp renders), REF_SAMPLES (1024, the references), FRAMES
# (1-1, a range A-B), DOF (1: also the lens reference and `shutter dof`; 0 skips; default 1
# for the fan, 0 for the gears, whose lens was focused for the fan's cube), FRESH (1: render
# again what is on disk), SHUTTER_BIN (a shutter binary; default: cargo build --release),
# PYTHON, BPY (as peers).
set -euo pipefail

here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
cd "$root"
SCENE=${SCENE:-fan}
case $SCENE in
  fan) OUT=${OUT:-target/layers/real} DOF=${DOF:-1} ;;
  gear-spin | gear-slide) OUT=${OUT:-target/layers/real-$SCENE} DOF=${DOF:-0} ;;
  *) echo "layers: SCENE is fan, gear-spin or gear-slide, not $SCENE" >&2; exit 1 ;;
esac
SIZE=${SIZE:-480x270}
SAMPLES=${SAMPLES:-128}
REF_SAMPLES=${REF_SAMPLES:-1024}
FRAMES=${FRAMES:-1-1}
FRESH=${FRESH:-0}
BPY=${BPY:-5.2.3}
venv=target/peers/venv
first=${FRAMES%-*}
last=${FRAMES#*-}
frames=$(seq "$first" "$last")
# The lens of scene.py's LENS, for `shutter dof`.
lens=(--focal-length 35 --f-stop 1.4 --focus-distance 0.8 --sensor-width 36)

if [ -n "${SHUTTER_BIN:-}" ]; then
  shutter=$SHUTTER_BIN
else
  cargo build --release
  shutter=target/release/shutter
fi

if [ ! -x "$venv/bin/python" ]; then
  python=${PYTHON:-$(command -v python3.13 || true)}
  # (pyenv's shim for python3.13 exists, and fails, while 3.13 is installed but not selected.)
  if [ -n "$python" ] && ! "$python" -c '' 2>/dev/null; then python=; fi
  if [ -z "$python" ] && command -v pyenv >/dev/null; then
    python=$(pyenv root)/versions/$(pyenv versions --bare | grep '^3\.13' | tail -1)/bin/python
  fi
  [ -x "$python" ] || { echo "layers: need Python 3.13 for bpy $BPY (set PYTHON)" >&2; exit 1; }
  "$python" -m venv "$venv"
fi
"$venv/bin/python" -m pip install --quiet "bpy==$BPY" OpenEXR numpy
py=$venv/bin/python

mkdir -p "$OUT"
# render NAME SCENE_ARGS...: renders OUT/NAME.####.exr unless every frame is there (FRESH=1
# renders again), and appends its wall time to OUT/times.txt.
render() {
  local name=$1 have=1 f
  shift
  for f in $frames; do [ -f "$(printf '%s/%s.%04d.exr' "$OUT" "$name" "$f")" ] || have=0; done
  if [ "$have" = 1 ] && [ "$FRESH" != 1 ]; then
    echo "layers: $name on disk" >&2
    return
  fi
  echo "layers: rendering $name" >&2
  local t0=$SECONDS
  "$py" "$here/scene.py" "$OUT" "$@" --scene "$SCENE" --name "$name" --size "$SIZE" \
    --frames "$FRAMES" >/dev/null
  echo "$name $* $((SECONDS - t0)) s" | tee -a "$OUT/times.txt" >&2
}
render layers layers --others holdout --samples "$SAMPLES"
render fg_exclude fg --others exclude --samples "$SAMPLES"
render fg_indirect fg --others indirect --samples "$SAMPLES"
render single single --samples "$SAMPLES"
render reference reference --samples "$REF_SAMPLES"
render reference_seed2 reference --samples "$REF_SAMPLES" --seed 2
render reference_fg reference_fg --others exclude --samples "$REF_SAMPLES"
render reference_fg_seed2 reference_fg --others exclude --samples "$REF_SAMPLES" --seed 2
if [ "$DOF" = 1 ]; then
  render reference_dof reference_dof --samples "$REF_SAMPLES"
  render reference_dof_seed2 reference_dof --samples "$REF_SAMPLES" --seed 2
fi

for f in $frames; do
  "$py" "$here/check.py" facts "$OUT" "$f"
done | tee "$OUT/facts.txt"

blur=$OUT/blur
score=$OUT/score
rm -rf "$blur" "$score"
mkdir -p "$blur" "$score"
q=(--preset blender --beauty-only --frames "$FRAMES" -q)
# rgba IN OUT LAYER: a copy of LAYER's Combined as R, G, B, A, for shutter diff (every file
# scored holds the same four channels).
rgba() {
  local f
  for f in $frames; do
    oiiotool "$(printf "$1" "$f")" \
      --ch "R=$3.Combined.R,G=$3.Combined.G,B=$3.Combined.B,A=$3.Combined.A" \
      -o "$(printf "$2" "$f")"
  done
}
# over FG BG OUT: FG over BG, both premultiplied (oiiotool finds FG.Combined.A as alpha).
over() {
  local f
  for f in $frames; do
    oiiotool "$(printf "$1" "$f")" "$(printf "$2" "$f")" --over -o "$(printf "$3" "$f")"
  done
}
rgba "$OUT/reference.%04d.exr" "$score/reference.%04d.exr" ViewLayer
rgba "$OUT/reference_seed2.%04d.exr" "$score/reference_seed2.%04d.exr" ViewLayer
rgba "$OUT/single.%04d.exr" "$score/none.%04d.exr" ViewLayer
rgba "$OUT/reference_fg.%04d.exr" "$score/reference_fg.%04d.exr" FG
rgba "$OUT/reference_fg_seed2.%04d.exr" "$score/reference_fg_seed2.%04d.exr" FG
rgba "$OUT/layers.%04d.exr" "$score/fg_none.%04d.exr" FG
layers=$OUT/layers.####.exr
for alg in reconstruct scatter stretch; do
  b=(blur "${q[@]}" --algorithm "$alg")
  "$shutter" "${b[@]}" --color "$OUT/single.####.exr" -o "$blur/single_$alg.####.exr"
  "$shutter" "${b[@]}" --layer FG --color "$layers" -o "$blur/fg_$alg.####.exr"
  "$shutter" "${b[@]}" --layer BG --color "$layers" -o "$blur/bg_$alg.####.exr"
  "$shutter" "${b[@]}" --color "$OUT/fg_exclude.####.exr" -o "$blur/fg_exclude_$alg.####.exr"
  for fg in fg fg_exclude; do
    merged=${fg/fg/merged}
    over "$blur/${fg}_$alg.%04d.exr" "$blur/bg_$alg.%04d.exr" "$blur/${merged}_$alg.%04d.exr"
    rgba "$blur/${merged}_$alg.%04d.exr" "$score/${merged}_$alg.%04d.exr" FG
    rgba "$blur/${fg}_$alg.%04d.exr" "$score/${fg}_$alg.%04d.exr" FG
  done
  rgba "$blur/single_$alg.%04d.exr" "$score/single_$alg.%04d.exr" ViewLayer
  # The stack: each layer blurred alone and merged by shutter (the merge is R, G, B, A).
  "$shutter" "${b[@]}" --layers FG,BG --color "$layers" -o "$score/stack_$alg.####.exr"
  "$shutter" "${b[@]}" --layers FG,BG --color "$OUT/fg_exclude.####.exr" --color "$layers" \
    -o "$score/stack_exclude_$alg.####.exr"
done
# diff NAME REFERENCE [SHARP]: region RMSE (the pixels where the reference differs from the
# sharp frame, default none: the single layer's beauty) into score/NAME.json.
diff_() {
  "$shutter" diff "$score/$2.####.exr" "$score/$1.####.exr" \
    --sharp "$score/${3:-none}.####.exr" --frames "$FRAMES" --json -q >"$score/$1.json" ||
    [ $? = 1 ]
}
diff_ reference_seed2 reference
mv "$score/reference_seed2.json" "$score/noise.json"
diff_ reference_fg_seed2 reference_fg fg_none
mv "$score/reference_fg_seed2.json" "$score/fg_noise.json"
diff_ none reference
diff_ fg_none reference_fg fg_none
for alg in reconstruct scatter stretch; do
  for name in single merged merged_exclude stack stack_exclude; do diff_ "${name}_$alg" reference; done
  for name in fg fg_exclude; do diff_ "${name}_$alg" reference_fg fg_none; done
done

if [ "$DOF" = 1 ]; then
  rgba "$OUT/reference_dof.%04d.exr" "$score/reference_dof.%04d.exr" ViewLayer
  rgba "$OUT/reference_dof_seed2.%04d.exr" "$score/reference_dof_seed2.%04d.exr" ViewLayer
  for f in $frames; do
    cp "$(printf '%s/none.%04d.exr' "$score" "$f")" "$(printf '%s/dof_none.%04d.exr' "$score" "$f")"
  done
  for m in gather blend; do
    d=(dof "${q[@]}" "${lens[@]}" --method "$m")
    "$shutter" "${d[@]}" --color "$OUT/single.####.exr" -o "$blur/dof_single_$m.####.exr"
    "$shutter" "${d[@]}" --layer FG --color "$layers" -o "$blur/dof_fg_$m.####.exr"
    "$shutter" "${d[@]}" --layer BG --color "$layers" -o "$blur/dof_bg_$m.####.exr"
    over "$blur/dof_fg_$m.%04d.exr" "$blur/dof_bg_$m.%04d.exr" "$blur/dof_merged_$m.%04d.exr"
    rgba "$blur/dof_single_$m.%04d.exr" "$score/dof_single_$m.%04d.exr" ViewLayer
    rgba "$blur/dof_merged_$m.%04d.exr" "$score/dof_merged_$m.%04d.exr" FG
    "$shutter" "${d[@]}" --layers FG,BG --color "$layers" -o "$score/dof_stack_$m.####.exr"
  done
  diff_ reference_dof_seed2 reference_dof
  mv "$score/reference_dof_seed2.json" "$score/dof_noise.json"
  for name in dof_none dof_single_gather dof_merged_gather dof_single_blend dof_merged_blend \
    dof_stack_gather dof_stack_blend; do
    diff_ "$name" reference_dof
  done
fi

# shellcheck disable=SC2086
"$py" "$here/check.py" table "$OUT" $frames | tee "$OUT/table.md"
