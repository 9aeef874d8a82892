#!/usr/bin/env bash
# Opt-in test (README, "On a farm"; not run by CI): the Open Job Description template
# farm/openjd/shutter-blur.yaml, validated and run end to end by openjd-cli, writes the same
# bytes as one local `shutter blur` run, and a retried chunk resumes.
#
#   scripts/farm/openjd-test.sh
#
# Steps: openjd-cli from PyPI into target/farm/venv (OPENJD_CLI, default 0.8.0, the newest in
# 2026-12, which runs TASK_CHUNKING); shutter built in release; a generated sequence
# (`shutter scene rotor`, 96x54, FRAMES frames, default 7); `openjd check`; `openjd run` over
# every frame in chunks of CHUNK (default 3, which does not divide 7); one local
# `shutter blur` over the same frames (which must change them: a comparison of unblurred
# copies would prove little); cmp of every output and no stray files (temporary files,
# locks). Then a retry: one output removed and another cut short, the chunks holding them run
# again through the template; exactly those two must be rewritten and all outputs must again
# equal the local run's. Exit 0 when everything holds; each step's time is printed.
set -euo pipefail
trap 'echo "openjd-test: FAIL: line $LINENO: $BASH_COMMAND exited $?" >&2' ERR

root=$(cd "$(dirname "$0")/../.." && pwd)
cd "$root"
FRAMES=${FRAMES:-7}
CHUNK=${CHUNK:-3}
ALGORITHM=${ALGORITHM:-reconstruct}
OPENJD_CLI=${OPENJD_CLI:-0.8.0}
PYTHON=${PYTHON:-python3}
venv=$root/target/farm/venv
work=$root/target/farm/openjd
template=$root/farm/openjd/shutter-blur.yaml

t0=$SECONDS
step() {
  echo "openjd-test: [$((SECONDS - t0)) s] $*" >&2
}
fail() {
  echo "openjd-test: FAIL: $*" >&2
  exit 1
}

step "openjd-cli $OPENJD_CLI into $venv"
[ -x "$venv/bin/python" ] || "$PYTHON" -m venv "$venv"
"$venv/bin/python" -m pip install --quiet --disable-pip-version-check "openjd-cli==$OPENJD_CLI"
openjd=$venv/bin/openjd

step "building shutter (release)"
cargo build --release --quiet
shutter=$root/target/release/shutter

rm -rf "$work"
mkdir -p "$work"
seq=$work/seq
step "generating a sequence: rotor, 96x54, $FRAMES frames"
"$shutter" scene rotor -o "$seq" --size 96x54 --frames "$FRAMES" --samples 4 >/dev/null

step "openjd check"
"$openjd" check "$template"

params=(
  -p "ShutterBinary=$shutter"
  -p "ColorPattern=$seq/color.####.exr"
  -p "DepthPattern=$seq/depth.####.exr"
  -p "VelocityPattern=$seq/velocity.####.exr"
  -p "OutputPattern=$work/farm/blur.####.exr"
  -p "Frames=1-$FRAMES"
  -p "ChunkSize=$CHUNK"
  -p "Algorithm=$ALGORITHM"
)
step "openjd run: frames 1-$FRAMES in chunks of $CHUNK"
"$openjd" run "$template" --step Blur "${params[@]}" >"$work/run.log" 2>&1 ||
  { tail -40 "$work/run.log" >&2; fail "openjd run failed (log: $work/run.log)"; }
chunks=$(grep -c 'Frame(CHUNK\[INT\]) = ' "$work/run.log" || true)
echo "openjd-test: chunks run: $(grep -o 'Frame(CHUNK\[INT\]) = .*' "$work/run.log" | cut -d' ' -f3 | paste -sd' ')" >&2
[ "$chunks" -ge 2 ] || fail "expected several chunks, openjd ran $chunks"

step "one local shutter blur over the same frames"
"$shutter" blur --frames "1-$FRAMES" --color "$seq/color.####.exr" --depth "$seq/depth.####.exr" \
  --velocity "$seq/velocity.####.exr" --algorithm "$ALGORITHM" -o "$work/local/blur.####.exr"

# The comparison proves something only if the blur changes the frames.
"$shutter" blur --frames 2 --color "$seq/color.####.exr" --algorithm none -o "$work/none/none.####.exr"
if cmp -s "$work/none/none.0002.exr" "$work/local/blur.0002.exr"; then
  fail "--algorithm $ALGORITHM left frame 2 as it was: the comparison would prove little"
fi

# The farm's folder holds exactly the local run's files (no temporary file, lock or probe
# left), each the same bytes.
same_outputs() {
  local what=$1 local_list farm_list f
  local_list=$(cd "$work/local" && find . -mindepth 1 | sort)
  farm_list=$(cd "$work/farm" && find . -mindepth 1 | sort)
  [ "$local_list" = "$farm_list" ] ||
    fail "$what: the farm's files differ from the local run's:"$'\n'"$(diff <(echo "$local_list") <(echo "$farm_list"))"
  [ "$(echo "$farm_list" | wc -l)" -eq "$FRAMES" ] || fail "$what: expected $FRAMES outputs: $farm_list"
  for f in "$work"/local/*; do
    cmp "$f" "$work/farm/${f##*/}" || fail "$what: ${f##*/} differs from the local run's"
  done
  echo "openjd-test: $what: $FRAMES outputs byte-identical to the local run, no stray files" >&2
}
same_outputs "openjd run"

# A retry: frame 2's output is gone and frame 5's cut short (as a killed task without
# atomic writes would leave it); rerunning the chunks that hold them rewrites those two
# and skips the rest.
step "retry: frame 2 removed, frame 5 cut short, their chunks run again"
rm "$work/farm/blur.0002.exr"
head -c 100 "$work/local/blur.0005.exr" >"$work/farm/blur.0005.exr"
tasks=$(grep -o 'Frame(CHUNK\[INT\]) = .*' "$work/run.log" | cut -d' ' -f3 |
  while read -r c; do
    for f in 2 5; do
      if "$shutter" frames "$c" --chunk-size 1 | grep -qx -- "$f"; then
        printf '{"Frame": "%s"}\n' "$c"
        break
      fi
    done
  done | paste -sd, -)
"$openjd" run "$template" --step Blur "${params[@]}" --tasks "[$tasks]" >"$work/retry.log" 2>&1 ||
  { tail -40 "$work/retry.log" >&2; fail "openjd run (retry) failed (log: $work/retry.log)"; }
wrote=$(grep -o 'shutter: wrote .*' "$work/retry.log" | sed 's/.*\///' | sort | paste -sd' ')
[ "$wrote" = "blur.0002.exr blur.0005.exr" ] ||
  fail "the retry should rewrite frames 2 and 5 alone and skip the rest; it wrote: ${wrote:-nothing}"
same_outputs "retry"

step "done"
echo "openjd-test: PASS in $((SECONDS - t0)) s" >&2
