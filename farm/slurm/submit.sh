#!/usr/bin/env bash
# Submits farm/slurm/shutter-array.sh as a job array with one task per chunk of frames.
#
#   SHUTTER_FRAMES=1001-1100 SHUTTER_CHUNK_SIZE=10 SHUTTER_COLOR=/shots/sh010/color.####.exr \
#   SHUTTER_VELOCITY=/shots/sh010/velocity.####.exr SHUTTER_OUTPUT=/shots/sh010/blur/blur.####.exr \
#       farm/slurm/submit.sh [SBATCH OPTIONS...]
#
# The SHUTTER_* settings are those of shutter-array.sh, passed to the tasks in the
# environment. SHUTTER_LOGS (default: logs) is the folder for the tasks' logs, one per task,
# JOBID_TASK.log. Options after the script's name go to sbatch (--partition, --time,
# --cpus-per-task, --wait, ...). Prints sbatch's output (the job id).
set -euo pipefail

here=$(cd "$(dirname "$0")" && pwd)
: "${SHUTTER_FRAMES:?set SHUTTER_FRAMES to the frames, e.g. 1001-1100}"
: "${SHUTTER_CHUNK_SIZE:?set SHUTTER_CHUNK_SIZE to the frames per array task}"
: "${SHUTTER_COLOR:?set SHUTTER_COLOR to the colour pass pattern}"
: "${SHUTTER_OUTPUT:?set SHUTTER_OUTPUT to the output pattern}"
shutter=${SHUTTER_BIN:-shutter}
logs=${SHUTTER_LOGS:-logs}

# A bad spec or chunk size fails here (exit 2), before anything is queued.
chunks=$("$shutter" frames "$SHUTTER_FRAMES" --chunk-size "$SHUTTER_CHUNK_SIZE" --count)
mkdir -p "$logs"
echo "submit: $SHUTTER_FRAMES in $chunks chunks of at most $SHUTTER_CHUNK_SIZE frames; logs in $logs/" >&2
export SHUTTER_FRAMES SHUTTER_CHUNK_SIZE SHUTTER_COLOR SHUTTER_OUTPUT
exec sbatch --array="0-$((chunks - 1))" --output="$logs/%A_%a.log" --export=ALL "$@" \
  "$here/shutter-array.sh"
