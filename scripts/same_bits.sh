#!/usr/bin/env bash
# Proves a refactor keeps every output bit-identical: runs two shutter binaries on the same
# inputs with every algorithm setting that matters and compares the outputs with cmp.
#
#   scripts/same_bits.sh BASE_BIN NEW_BIN FRAMES_DIR OUT_DIR
#
# FRAMES_DIR holds input sets, one folder each, in the canonical convention
# (color/depth/velocity/prev/next.####.exr):
#   FRAMES_DIR/scenes/NAME  `shutter scene NAME -o FRAMES_DIR/scenes/NAME --samples 4`
#   FRAMES_DIR/bench/NAME   `cargo run --release --example bench_frames -- FRAMES_DIR/bench`
#                           (the processing benches' 1920x1080 frames)
# A set gets the cases its passes allow: none always; reconstruct and stretch with velocity;
# scatter with prev and next; depth of field where a lens is known (scene.json's "lens", or
# a lens.args file of `shutter dof` flags).
#
# Prints one line per case (same / DIFFERS / FAILED(base rc,new rc)) and a summary; exits 1
# if anything differs or failed, 2 on a usage error. THREADS (default 2) sets --threads;
# BACKEND (default cpu) sets --backend (wgpu: the GPU twins, on whatever adapter wgpu finds,
# lavapipe included); KEEP_BASE=1 reuses the base outputs a previous run left in OUT_DIR
# (the base binary is then run only for cases it has no output for); ONLY (a regular
# expression) runs only the cases whose set/name matches it.
set -u

if [ $# -ne 4 ]; then
    echo "usage: $0 BASE_BIN NEW_BIN FRAMES_DIR OUT_DIR" >&2
    exit 2
fi
BASE_BIN=$1
NEW_BIN=$2
FRAMES=$3
OUT=$4
THREADS=${THREADS:-2}
BACKEND=${BACKEND:-cpu}
KEEP_BASE=${KEEP_BASE:-0}
ONLY=${ONLY:-}
for bin in "$BASE_BIN" "$NEW_BIN"; do
    [ -x "$bin" ] || { echo "not an executable: $bin" >&2; exit 2; }
done
[ -d "$FRAMES" ] || { echo "no such folder: $FRAMES" >&2; exit 2; }
mkdir -p "$OUT"

same=0
differ=0
failed=0
start=$SECONDS

# run SET_DIR SET_NAME CASE_NAME SUBCOMMAND ARGS...
run() {
    local dir=$1 set=$2 name=$3 cmd=$4
    shift 4
    if [ -n "$ONLY" ] && ! [[ "$set/$name" =~ $ONLY ]]; then
        return
    fi
    local passes=(--color "$dir/color.####.exr")
    local role
    for role in depth velocity prev next; do
        if [ -e "$dir/$role.0001.exr" ]; then
            passes+=("--$role" "$dir/$role.####.exr")
        fi
    done
    local rcs=() side
    for side in base new; do
        local bin=$BASE_BIN
        [ $side = new ] && bin=$NEW_BIN
        local out="$OUT/$side/$set/$name"
        if [ $side = base ] && [ "$KEEP_BASE" = 1 ] && [ -n "$(ls "$out" 2>/dev/null)" ]; then
            rcs+=(0)
            continue
        fi
        rm -rf "$out"
        mkdir -p "$out" "$OUT/logs/$side/$set"
        "$bin" "$cmd" "${passes[@]}" "$@" --backend "$BACKEND" --threads "$THREADS" \
            -o "$out/out.####.exr" >"$OUT/logs/$side/$set/$name.log" 2>&1
        rcs+=($?)
    done
    local case_name="$set/$name"
    if [ "${rcs[0]}" -ne 0 ] || [ "${rcs[1]}" -ne 0 ]; then
        printf 'FAILED(%s,%s) %s  [%s %s]\n' "${rcs[0]}" "${rcs[1]}" "$case_name" "$cmd" "$*"
        failed=$((failed + 1))
        return
    fi
    local a="$OUT/base/$set/$name" b="$OUT/new/$set/$name"
    local list_a list_b
    list_a=$(cd "$a" && ls)
    list_b=$(cd "$b" && ls)
    if [ -z "$list_a" ] || [ "$list_a" != "$list_b" ]; then
        printf 'FAILED(outputs) %s  [%s %s]: base wrote {%s}, new wrote {%s}\n' \
            "$case_name" "$cmd" "$*" "$list_a" "$list_b"
        failed=$((failed + 1))
        return
    fi
    local f ok=1
    for f in $list_a; do
        cmp -s "$a/$f" "$b/$f" || ok=0
    done
    if [ $ok = 1 ]; then
        printf 'same    %s\n' "$case_name"
        same=$((same + 1))
    else
        printf 'DIFFERS %s  [%s %s]\n' "$case_name" "$cmd" "$*"
        differ=$((differ + 1))
    fi
}

# The lens of a set as `shutter dof` flags, or nothing.
lens_args() {
    local dir=$1
    if [ -f "$dir/lens.args" ]; then
        cat "$dir/lens.args"
    elif [ -f "$dir/scene.json" ] && grep -q '"lens": {' "$dir/scene.json"; then
        awk '
            /"lens": \{/ { inside = 1; next }
            inside && /\}/ { inside = 0 }
            inside {
                gsub(/[",]/, ""); split($0, kv, ":"); key = kv[1]; gsub(/ /, "", key)
                value = kv[2]; gsub(/ /, "", value)
                if (key == "focal_mm") printf "--focal-length %s ", value
                if (key == "f_number") printf "--f-stop %s ", value
                if (key == "focus") printf "--focus-distance %s ", value
                if (key == "sensor_mm") printf "--sensor-width %s ", value
            }' "$dir/scene.json"
    fi
}

for group in scenes bench; do
    for dir in "$FRAMES/$group"/*/; do
        dir=${dir%/}
        [ -e "$dir/color.0001.exr" ] || continue
        set="$group/$(basename "$dir")"
        run "$dir" "$set" none blur --algorithm none
        if [ -e "$dir/velocity.0001.exr" ] && [ -e "$dir/depth.0001.exr" ]; then
            run "$dir" "$set" reconstruct blur --algorithm reconstruct
            run "$dir" "$set" reconstruct-dual blur --algorithm reconstruct --variant dual
            run "$dir" "$set" reconstruct-nojitter blur --algorithm reconstruct --no-jitter
            run "$dir" "$set" reconstruct-2014 blur --algorithm reconstruct --variant 2014
            run "$dir" "$set" reconstruct-paper blur --algorithm reconstruct --variant paper
            run "$dir" "$set" reconstruct-start blur --algorithm reconstruct --shutter-offset start
            run "$dir" "$set" reconstruct-paper-end blur --algorithm reconstruct --variant paper --shutter-offset end
            run "$dir" "$set" stretch blur --algorithm stretch
            run "$dir" "$set" stretch-rear blur --algorithm stretch --anchor rear
            run "$dir" "$set" stretch-notexture blur --algorithm stretch --no-texture-blur
            run "$dir" "$set" stretch-start blur --algorithm stretch --shutter-offset start
        fi
        if [ -e "$dir/prev.0001.exr" ] && [ -e "$dir/next.0001.exr" ] && [ -e "$dir/depth.0001.exr" ]; then
            run "$dir" "$set" scatter blur --algorithm scatter
            run "$dir" "$set" scatter-paper-gaussian blur --algorithm scatter --normalize paper --weight gaussian
            run "$dir" "$set" scatter-arc blur --algorithm scatter --curve arc
            run "$dir" "$set" scatter-end blur --algorithm scatter --shutter-offset end
            if [ "$set" = bench/scatter_moving ]; then
                # The scatter bench's own shutter (1.0: 30 px streaks).
                run "$dir" "$set" scatter-shutter1 blur --algorithm scatter --shutter 1
            fi
        fi
        lens=$(lens_args "$dir")
        if [ -n "$lens" ] && [ -e "$dir/depth.0001.exr" ]; then
            # shellcheck disable=SC2086 # the lens flags split into words on purpose
            {
                run "$dir" "$set" dof-gather dof $lens --method gather
                run "$dir" "$set" dof-gather-blades6 dof $lens --method gather --blades 6
                run "$dir" "$set" dof-blend dof $lens --method blend
                run "$dir" "$set" dof-blend-talk dof $lens --method blend --blend-form talk
                if [ -e "$dir/velocity.0001.exr" ]; then
                    run "$dir" "$set" dof-gather+reconstruct dof $lens --method gather --algorithm reconstruct
                fi
                if [ -e "$dir/prev.0001.exr" ] && [ -e "$dir/next.0001.exr" ]; then
                    run "$dir" "$set" dof-gather+scatter dof $lens --method gather --algorithm scatter
                fi
            }
        fi
    done
done

echo "$same same, $differ differ, $failed failed ($((SECONDS - start)) s)"
[ $differ -eq 0 ] && [ $failed -eq 0 ] && [ $same -gt 0 ]
