#!/usr/bin/env bash
# Blender's compositor as a peer column in `shutter bench` (README, "Peers"). Opt-in, not run
# by CI: it downloads bpy (about 400 MB) into target/peers/venv.
#
#   scripts/peers/run.sh [BENCH FLAGS...]
#
# Environment: OUT (default target/bench), SIZE (320x180, the bench's default), SCENES
# (comma-separated, default all), SAMPLES (reference samples, 1024), RUNS (timed runs, 5),
# PYTHON (a Python 3.13 for bpy 5.2.3; default python3.13 or pyenv's 3.13), BPY (5.2.3),
# BLENDER34 (Debian's blender binary, default `blender` where installed; "none" skips it).
#
# Steps: build shutter; make the scenes as the bench makes them (`shutter scene`, reused by
# the bench while their settings match); convert their passes to Blender's conventions
# (peers.py prepare); run Vector Blur and Defocus in bpy 5.2 and, where installed, Blender
# 3.4 (blender_peers.py); merge their lists into OUT/peers/peers.json; then
# `shutter bench --peers OUT/peers` scores everything in one run.
set -euo pipefail

here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
cd "$root"
OUT=${OUT:-target/bench}
SIZE=${SIZE:-320x180}
SAMPLES=${SAMPLES:-1024}
RUNS=${RUNS:-5}
BPY=${BPY:-5.2.3}
SCENES=${SCENES:-rotor,orbit,figure,crossing,pan,zoom,gears,static,sparse,huge,layers,border,border-coarse,border-cut,follow,follow-wall}
venv=target/peers/venv

cargo build --release
shutter=target/release/shutter

if [ ! -x "$venv/bin/python" ]; then
  python=${PYTHON:-$(command -v python3.13 || true)}
  # (pyenv's shim for python3.13 exists, and fails, while 3.13 is installed but not selected.)
  if [ -n "$python" ] && ! "$python" -c '' 2>/dev/null; then python=; fi
  if [ -z "$python" ] && command -v pyenv >/dev/null; then
    python=$(pyenv root)/versions/$(pyenv versions --bare | grep '^3\.13' | tail -1)/bin/python
  fi
  [ -x "$python" ] || { echo "peers: need Python 3.13 for bpy $BPY (set PYTHON)" >&2; exit 1; }
  "$python" -m venv "$venv"
fi
"$venv/bin/python" -m pip install --quiet "bpy==$BPY" OpenEXR numpy

IFS=, read -r -a scenes <<<"$SCENES"
for scene in "${scenes[@]}"; do
  dir="$OUT/scenes/$scene"
  want="$scene ${SIZE%x*} ${SIZE#*x} $SAMPLES"
  have=$("$venv/bin/python" -c 'import json,sys
try:
    d = json.load(open(sys.argv[1]))
    print(d["scene"], d["width"], d["height"], d["samples"])
except Exception:
    pass' "$dir/scene.json")
  if [ "$have" != "$want" ]; then
    echo "peers: making scene $scene" >&2
    "$shutter" scene "$scene" -o "$dir" --size "$SIZE" --samples "$SAMPLES"
  fi
done

rm -rf "$OUT/peers"
"$venv/bin/python" "$here/peers.py" prepare "$OUT" "${scenes[@]}"
"$venv/bin/python" "$here/blender_peers.py" "$OUT" "${scenes[@]}" --runs "$RUNS"
blender34=${BLENDER34:-$(command -v blender || true)}
if [ -n "$blender34" ] && [ "$blender34" != none ]; then
  "$blender34" -b --factory-startup --python-exit-code 1 --python "$here/blender_peers.py" \
    -- "$OUT" "${scenes[@]}" --runs "$RUNS"
else
  echo "peers: no Debian blender (apt-get install blender); Blender 3.4 rows left out" >&2
fi
"$venv/bin/python" "$here/peers.py" merge "$OUT"

"$shutter" bench --scenes "$SCENES" --size "$SIZE" --samples "$SAMPLES" --runs "$RUNS" \
  --out "$OUT" --peers "$OUT/peers" "$@"
