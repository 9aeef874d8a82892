#!/usr/bin/env bash
# Times two shutter binaries on the same 1920x1080 frames by alternating them (A, B, A, B, …)
# in one run, so the drift of a shared machine (25-50 % on the project's VMs) falls on both
# alike. Prints, per case, each binary's process_seconds per frame (from --json) for every
# round, their medians and the ratio B/A.
#
#   scripts/ab_time.sh A_BIN B_BIN FRAMES_DIR [ROUNDS]
#
# FRAMES_DIR is `cargo run --release --example bench_frames -- FRAMES_DIR` (moving,
# scatter_moving, static, sparse, dof). BACKEND (default cpu) sets --backend; ONLY (a regular
# expression) runs only the matching cases.
set -u

if [ $# -lt 3 ]; then
    echo "usage: $0 A_BIN B_BIN FRAMES_DIR [ROUNDS]" >&2
    exit 2
fi
A=$1
B=$2
FRAMES=$3
ROUNDS=${4:-5}
BACKEND=${BACKEND:-cpu}
ONLY=${ONLY:-}
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT

# seconds BIN SET ARGS...: process_seconds per frame of one run.
seconds() {
    local bin=$1 set=$2
    shift 2
    local dir=$FRAMES/$set
    local passes=(--color "$dir/color.####.exr")
    local role
    for role in depth velocity prev next; do
        [ -e "$dir/$role.0001.exr" ] && passes+=("--$role" "$dir/$role.####.exr")
    done
    rm -f "$OUT"/o.*
    "$bin" "$@" "${passes[@]}" --backend "$BACKEND" -o "$OUT/o.####.exr" --json 2>/dev/null |
        python3 -c 'import json, sys; j = json.load(sys.stdin); print(j["process_seconds"] / max(j["frames_written"], 1))'
}

# case NAME SET ARGS...
case_() {
    local name=$1
    shift
    if [ -n "$ONLY" ] && ! [[ "$name" =~ $ONLY ]]; then
        return
    fi
    local a=() b=() r
    for ((r = 0; r < ROUNDS; r++)); do
        a+=("$(seconds "$A" "$@")")
        b+=("$(seconds "$B" "$@")")
    done
    python3 - "$name" "${a[*]}" "${b[*]}" <<'EOF'
import statistics, sys
name, a, b = sys.argv[1], [float(x) for x in sys.argv[2].split()], [float(x) for x in sys.argv[3].split()]
ma, mb = statistics.median(a), statistics.median(b)
fmt = lambda xs: " ".join(f"{x * 1e3:.0f}" for x in xs)
print(f"{name:28s} A {ma * 1e3:7.1f} ms [{fmt(a)}]  B {mb * 1e3:7.1f} ms [{fmt(b)}]  B/A {mb / ma:.3f}")
EOF
}

lens=$(cat "$FRAMES/dof/lens.args")
# shellcheck disable=SC2086 # the lens flags split into words on purpose
{
    case_ none moving blur --algorithm none
    case_ reconstruct moving blur --algorithm reconstruct
    case_ reconstruct-2014 moving blur --algorithm reconstruct --variant 2014
    case_ reconstruct-paper moving blur --algorithm reconstruct --variant paper
    case_ reconstruct-sparse sparse blur --algorithm reconstruct
    case_ scatter scatter_moving blur --algorithm scatter
    case_ scatter-sparse sparse blur --algorithm scatter
    case_ stretch moving blur --algorithm stretch
    case_ dof-gather dof dof $lens --method gather
    case_ dof-blend dof dof $lens --method blend
    case_ dof-blend-talk dof dof $lens --method blend --blend-form talk
    case_ static-reconstruct static blur --algorithm reconstruct
}
