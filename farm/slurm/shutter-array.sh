#!/usr/bin/env bash
# shutter blur as a Slurm job array: array task K processes chunk K of the frames (from 0).
#
# Submit with farm/slurm/submit.sh (it counts the chunks and sets --array), or by hand:
#
#   export SHUTTER_FRAMES=1001-1100 SHUTTER_CHUNK_SIZE=10 \
#       SHUTTER_COLOR=/shots/sh010/color.####.exr SHUTTER_VELOCITY=/shots/sh010/velocity.####.exr \
#       SHUTTER_DEPTH=/shots/sh010/depth.####.exr SHUTTER_OUTPUT=/shots/sh010/blur/blur.####.exr
#   n=$(shutter frames "$SHUTTER_FRAMES" --chunk-size "$SHUTTER_CHUNK_SIZE" --count)
#   mkdir -p logs && sbatch --array=0-$((n - 1)) --output='logs/%A_%a.log' farm/slurm/shutter-array.sh
#
# Settings come from the environment (sbatch passes the submitter's on by default):
#   SHUTTER_FRAMES       frames, a range expression (1001-1100, 1-100:5, 1,3,7-20:2)   required
#   SHUTTER_CHUNK_SIZE   frames per array task                                          required
#   SHUTTER_COLOR        colour pass pattern                                            required
#   SHUTTER_OUTPUT       output pattern                                                 required
#   SHUTTER_DEPTH, SHUTTER_VELOCITY, SHUTTER_PREV, SHUTTER_NEXT   other passes (default: as the
#                        preset finds them in the colour file)
#   SHUTTER_PRESETS      presets, comma-separated, later ones winning (default: shutter's own)
#   SHUTTER_ALGORITHM    none, reconstruct, scatter or stretch (default: the presets')
#   SHUTTER_THREADS      worker threads (default: the CPUs Slurm gave the task)
#   SHUTTER_BIN          the shutter executable (default: shutter on PATH)
#   SHUTTER_MAX_REQUEUES how many times a task requeues itself after a transient failure (3)
#
# Every run passes --skip-existing, so a task that runs again (requeued, or resubmitted by
# hand) keeps the whole frames already written and writes the rest; frames are written to a
# temporary file and renamed, a killed run's temporary files are removed by the next run
# over the same outputs, and a per-frame lock keeps two runs off the same frames.
#
# Exit codes (shutter's):
#   0   the chunk is done.
#   1   a problem with an input or output file (missing, corrupt, clashing): fails the task;
#       rerunning will not help until the files are fixed.
#   2   a usage error (a bad setting): fails the task.
#   75  transient (EX_TEMPFAIL: another job holds a frame's lock, or a write failed with an
#       error a retry may cure: a full disk or quota, an interrupted or timed-out write; one
#       that cannot, permissions or a read-only file system, is 1): the task requeues itself with `scontrol requeue` and runs again later,
#       up to SHUTTER_MAX_REQUEUES times, then fails with 75. Slurm holds a requeued job back
#       for its credential lifetime (AuthInfo cred_expire, 120 s by default) before it can
#       start again, which gives the other job time to finish. Requeueing from inside the
#       task needs no site configuration; a site that sets RequeueExit=75 in slurm.conf can
#       set SHUTTER_MAX_REQUEUES=0 and let Slurm requeue on the exit code instead.
#   130, 143  shutter stopped on SIGINT / SIGTERM (scancel, the time limit and preemption send
#       SIGTERM first), having removed its temporary files: Slurm's own requeue (preemption)
#       or a resubmission of the same array resumes it.
#SBATCH --job-name=shutter-blur
#SBATCH --output=shutter-%A_%a.log
#SBATCH --requeue
#SBATCH --open-mode=append
set -euo pipefail

die() {
  echo "shutter-array: $*" >&2
  exit 2
}

: "${SLURM_ARRAY_TASK_ID:?not an array task: submit with sbatch --array=0-N (see farm/slurm/submit.sh)}"
: "${SHUTTER_FRAMES:?set SHUTTER_FRAMES to the frames, e.g. 1001-1100}"
: "${SHUTTER_CHUNK_SIZE:?set SHUTTER_CHUNK_SIZE to the frames per array task}"
: "${SHUTTER_COLOR:?set SHUTTER_COLOR to the colour pass pattern}"
: "${SHUTTER_OUTPUT:?set SHUTTER_OUTPUT to the output pattern}"
shutter=${SHUTTER_BIN:-shutter}
max_requeues=${SHUTTER_MAX_REQUEUES:-3}
restarts=${SLURM_RESTART_COUNT:-0}

# This task's frames, as the submitter counted them: `shutter frames` cuts the spec the same
# way on every host, every frame in exactly one chunk.
frames=$("$shutter" frames "$SHUTTER_FRAMES" --chunk-size "$SHUTTER_CHUNK_SIZE" \
  --chunk "$SLURM_ARRAY_TASK_ID") || die "cannot cut $SHUTTER_FRAMES into chunks of $SHUTTER_CHUNK_SIZE"

args=(blur --frames "$frames" --color "$SHUTTER_COLOR" -o "$SHUTTER_OUTPUT" --skip-existing --verbose)
[ -n "${SHUTTER_DEPTH:-}" ] && args+=(--depth "$SHUTTER_DEPTH")
[ -n "${SHUTTER_VELOCITY:-}" ] && args+=(--velocity "$SHUTTER_VELOCITY")
[ -n "${SHUTTER_PREV:-}" ] && args+=(--prev "$SHUTTER_PREV")
[ -n "${SHUTTER_NEXT:-}" ] && args+=(--next "$SHUTTER_NEXT")
if [ -n "${SHUTTER_PRESETS:-}" ]; then
  IFS=, read -r -a presets <<<"$SHUTTER_PRESETS"
  for preset in "${presets[@]}"; do args+=(--preset "$preset"); done
fi
[ -n "${SHUTTER_ALGORITHM:-}" ] && args+=(--algorithm "$SHUTTER_ALGORITHM")
threads=${SHUTTER_THREADS:-${SLURM_CPUS_PER_TASK:-${SLURM_CPUS_ON_NODE:-}}}
[ -n "$threads" ] && args+=(--threads "$threads")

echo "shutter-array: job ${SLURM_ARRAY_JOB_ID:-?}_$SLURM_ARRAY_TASK_ID (job id ${SLURM_JOB_ID:-?})," \
  "attempt $((restarts + 1)), on $(hostname), frames $frames" >&2
start=$SECONDS
rc=0
"$shutter" "${args[@]}" || rc=$?
echo "shutter-array: shutter exited $rc after $((SECONDS - start)) s" >&2

case $rc in
  0) exit 0 ;;
  75)
    if [ "$restarts" -lt "$max_requeues" ] && [ -n "${SLURM_JOB_ID:-}" ]; then
      echo "shutter-array: transient failure; requeueing (requeue $((restarts + 1)) of $max_requeues)" >&2
      # Ends this run; the task goes back to pending and starts again with --skip-existing.
      scontrol requeue "$SLURM_JOB_ID" || echo "shutter-array: scontrol requeue failed" >&2
    else
      echo "shutter-array: transient failure, requeued $restarts times already: giving up" >&2
    fi
    exit 75
    ;;
  1) echo "shutter-array: bad input or output file (see above): not retrying" >&2 ;;
  2) echo "shutter-array: usage error (check the SHUTTER_* settings): not retrying" >&2 ;;
  *) echo "shutter-array: stopped (exit $rc)" >&2 ;;
esac
exit "$rc"
