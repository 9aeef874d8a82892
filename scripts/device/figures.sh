#!/usr/bin/env bash
# The hardware figures issues 15 and 16 ask for, in one short run on a lent GPU machine (the
# device tool: one chip, 15 minutes of device time a session, no network, so nothing is built
# or downloaded there).
#
#   scripts/device/figures.sh --prepare     # here: build, strip into target/device/ (~60 MiB)
#                                           # and pack it as target/device.tar.xz (~14 MiB)
#   OUT=$OUT scripts/device/figures.sh      # there, with carry ["target/device.tar.xz"]
#
# Records, under OUT (default target/device-figures):
# - hardware.txt: nvidia-smi, the CPU, the adapter wgpu picks;
# - bench-*.txt: `cargo bench` for reconstruct, the depth of field's GPU rows, scatter and
#   stretch (the 1920×1080 frames, GPU stages timed apart: upload, compute, readback);
# - sequence.tsv and sequence/*.json: a 1920×1080 sequence (`shutter scene layers`, FRAMES
#   frames) through `shutter blur`/`dof` with every algorithm on --backend wgpu and cpu, against
#   --algorithm none (the I/O floor: decode, copy, encode), each run's --json kept;
# - parity.txt: the GPU parity tests (the integration tests whose names hold `gpu`, built with
#   `cargo test --release --no-run`) run on that machine's adapter, GPU required: the twins
#   were tested on lavapipe alone until the first hardware run (2026-12-04) found NVIDIA's
#   driver fusing products that lavapipe rounds apart (docs/history/device-parity-2026-12-04.md);
# - figures.md: the tables BENCHMARKS.md takes, with this command, and the parity summary.
#
# Environment: OUT; FRAMES (24); SIZE (1920x1080); BENCHES (the benches to run, default
# "reconstruct dof scatter stretch"; empty: none); SHUTTER (the binary; target/device/shutter,
# else target/release/shutter). Every step has its own time limit, so a slow step costs that
# step, not the run; a failed step is recorded and the rest go on.
set -uo pipefail

here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
cd "$root"

if [ "${1:-}" = "--prepare" ]; then
  set -e
  cargo build --release
  cargo bench --no-run --bench reconstruct --bench dof --bench scatter --bench stretch 2>&1 |
    tee target/device-prepare.log
  mkdir -p target/device
  strip -o target/device/shutter "${CARGO_TARGET_DIR:-target}/release/shutter"
  for b in reconstruct dof scatter stretch; do
    # The newest build of each bench (cargo prints its path; the hash changes with the code).
    path=$(sed -n "s/.*Executable benches\/$b.rs (\(.*\))/\1/p" target/device-prepare.log | tail -1)
    strip -o "target/device/bench-$b" "$path"
  done
  cargo test --release --no-run 2>&1 | tee target/device-tests.log
  path=$(sed -n "s/.*Executable tests\/main.rs (\(.*\))/\1/p" target/device-tests.log | tail -1)
  strip -o target/device/test-integration "$path"
  # The tests read their fixtures under the folder they were built in.
  echo "$root" >target/device/root.txt
  du -sh target/device
  tar cJf target/device.tar.xz -C target device
  du -sh target/device.tar.xz
  exit 0
fi

# The archive, where it came, replaces what an earlier call left (a warm machine keeps
# ignored outputs between calls).
if [ -f target/device.tar.xz ]; then
  rm -rf target/device
  tar xJf target/device.tar.xz -C target
fi

OUT=${OUT:-target/device-figures}
FRAMES=${FRAMES:-24}
SIZE=${SIZE:-1920x1080}
BENCHES=${BENCHES-reconstruct dof scatter stretch}
shutter=${SHUTTER:-target/device/shutter}
[ -x "$shutter" ] || shutter=target/release/shutter
[ -x "$shutter" ] || { echo "figures: no shutter binary (run --prepare here first)" >&2; exit 1; }
mkdir -p "$OUT/sequence"
log() { echo "figures: $*" >&2; }
started=$(date +%s)

{
  date -u
  nvidia-smi 2>&1 || echo "nvidia-smi: not found"
  lscpu 2>/dev/null | grep -E "Model name|^CPU\(s\)" || true
  free -g 2>/dev/null | head -2 || true
} >"$OUT/hardware.txt"

# The parity tests, on this machine's adapter, from the folder they were built in.
tests=target/device/test-integration
if [ -x "$tests" ]; then
  built=$(cat target/device/root.txt 2>/dev/null || echo "$root")
  if [ ! -e "$built" ]; then
    mkdir -p "$(dirname "$built")" && ln -s "$root" "$built" || log "cannot place $built"
  fi
  # Tests that spawn the binary find it where cargo built it.
  mkdir -p target/release && cp "$shutter" target/release/shutter
  log "parity tests"
  (cd "$built" && SHUTTER_REQUIRE_GPU=1 timeout 240 "$root/$tests" gpu --test-threads 8) \
    >"$OUT/parity.txt" 2>&1
  echo "(exit $?)" >>"$OUT/parity.txt"
fi

# The benches: their GPU rows are the per-frame figures (compute apart from the transfers).
for b in $BENCHES; do
  bin=target/device/bench-$b
  [ -x "$bin" ] || { log "no $bin: bench skipped"; continue; }
  filter=()
  [ "$b" = dof ] && filter=(wgpu)
  log "bench $b"
  timeout 150 "$bin" --bench "${filter[@]}" >"$OUT/bench-$b.txt" 2>&1 ||
    echo "(exit $?: stopped at its time limit or failed)" >>"$OUT/bench-$b.txt"
done

# The sequence: every algorithm on each backend against the I/O floor.
seq=$OUT/scene
log "scene layers $SIZE, $FRAMES frames"
timeout 120 "$shutter" scene layers --size "$SIZE" --frames "$FRAMES" --samples 1 -o "$seq" \
  >/dev/null 2>"$OUT/scene.log" || log "scene failed (see scene.log)"
passes=(--color "$seq/color.####.exr" --depth "$seq/depth.####.exr"
  --velocity "$seq/velocity.####.exr" --prev "$seq/prev.####.exr" --next "$seq/next.####.exr")
lens=(--focal-length 50 --f-stop 1.4 --focus-distance 3 --max-coc 32)
printf 'run\tbackend\tadapter\tframes\twall_s\tfps\tread_s\tprocess_s\twrite_s\tcontext_s\tstages_on_cpu\n' \
  >"$OUT/sequence.tsv"
run() { # name backend command...
  local name=$1 backend=$2
  shift 2
  local json=$OUT/sequence/$name-$backend.json
  rm -rf "$OUT/out"
  log "sequence $name on $backend"
  if timeout 120 "$shutter" "$@" "${passes[@]}" --backend "$backend" --json \
    -o "$OUT/out/f.####.exr" >"$json" 2>"$OUT/sequence/$name-$backend.log"; then
    python3 - "$json" "$name" "$backend" >>"$OUT/sequence.tsv" <<'EOF' || log "no python3: $json kept"
import json, sys
d = json.load(open(sys.argv[1]))
b = d.get("backend") or {}
n = d["frames_written"]
print("\t".join(str(v) for v in [sys.argv[2], b.get("used", sys.argv[3]), b.get("adapter"), n,
      round(d["wall_seconds"], 3), round(n / d["wall_seconds"], 2), round(d["read_seconds"], 3),
      round(d["process_seconds"], 3), round(d["write_seconds"], 3),
      round(b.get("context_seconds", 0.0), 3), b.get("stages_on_cpu")]))
EOF
  else
    printf '%s\t%s\tfailed or over its time limit\n' "$name" "$backend" >>"$OUT/sequence.tsv"
  fi
}
for round in 1 2; do
  run none cpu blur --algorithm none
  for backend in wgpu cpu; do
    run reconstruct "$backend" blur --algorithm reconstruct
    run scatter "$backend" blur --algorithm scatter
    run stretch "$backend" blur --algorithm stretch
    run gather "$backend" dof "${lens[@]}"
    run blend "$backend" dof "${lens[@]}" --method blend
    run gather+reconstruct "$backend" dof "${lens[@]}" --algorithm reconstruct
  done
  [ $(($(date +%s) - started)) -gt 420 ] && break
done
rm -rf "$OUT/out" "$seq"

{
  echo "# Hardware figures ($(date -u +%F))"
  echo
  echo '```sh'
  echo "OUT=$OUT FRAMES=$FRAMES SIZE=$SIZE scripts/device/figures.sh"
  echo '```'
  echo
  echo '## Hardware'
  echo '```'
  cat "$OUT/hardware.txt"
  echo '```'
  echo
  echo '## The benches'
  for b in reconstruct dof scatter stretch; do
    [ -f "$OUT/bench-$b.txt" ] || continue
    echo
    echo "### cargo bench --bench $b"
    echo '```'
    cat "$OUT/bench-$b.txt"
    echo '```'
  done
  if [ -f "$OUT/parity.txt" ]; then
    echo
    echo '## The GPU parity tests'
    echo '```'
    grep -E '^test result|^    [a-z0-9_:]+$|^\(exit' "$OUT/parity.txt"
    echo '```'
  fi
  echo
  echo "## A $SIZE sequence of $FRAMES frames, end to end (two rounds)"
  echo
  echo '```'
  cat "$OUT/sequence.tsv"
  echo '```'
} >"$OUT/figures.md"
log "done in $(($(date +%s) - started)) s: $OUT/figures.md"
