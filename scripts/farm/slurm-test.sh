#!/usr/bin/env bash
# Opt-in test (README, "On a farm"; not run by CI): farm/slurm/shutter-array.sh on a
# single-node Slurm cluster brought up here, with tasks stopped midway and requeued; the
# outputs must be the bytes of one local `shutter blur` run, with no stray files.
#
#   apt-get install -y slurm-wlm munge     # Debian's Slurm 22.05 and MUNGE
#   scripts/farm/slurm-test.sh             # as root: it starts munged, slurmctld, slurmd
#
# The cluster: one node (this host) on loopback, non-default ports (PORT and PORT + 1, default
# 16817), munged with a key generated for the run, state, spool, sockets and logs under
# target/farm/slurm, daemons started directly (no systemd) and stopped by their process ids
# when the test ends, whatever the outcome. Settings: FRAMES (default 15), CHUNK (4, which
# does not divide 15: chunks of 4, 4, 4 and 3), SIZE (640x360: a stopped task must still be
# running when its first frame appears), ALGORITHM (reconstruct).
#
# Steps: build shutter (release); make a sequence (`shutter scene pan`); one local run; start
# the cluster; submit the array with farm/slurm/submit.sh --wait, one CPU a task, SHUTTER_BIN
# pointing at a wrapper that records shutter's process id and makes array task 1's first
# attempt exit 75 (the script must requeue it itself). Once array task 0 has written its
# first frame and is writing another, SIGKILL its shutter (it leaves a temporary file and
# the lock file), and once task 2 has written its first frame, scancel it (SIGTERM); requeue
# both (scontrol requeue). Then: sbatch --wait returns 0, every task COMPLETED (tasks 0, 1 and
# 2 after one restart each), task 0's rerun removed the killed run's temporary file, and the
# output folder holds the local run's files, byte for byte, and nothing else.
set -euo pipefail
trap 'echo "slurm-test: FAIL: line $LINENO: $BASH_COMMAND exited $?" >&2' ERR

root=$(cd "$(dirname "$0")/../.." && pwd)
cd "$root"
FRAMES=${FRAMES:-15}
CHUNK=${CHUNK:-4}
SIZE=${SIZE:-640x360}
ALGORITHM=${ALGORITHM:-reconstruct}
PORT=${PORT:-16817}
work=$root/target/farm/slurm
export SLURM_CONF=$work/etc/slurm.conf

t0=$SECONDS
step() {
  echo "slurm-test: [$((SECONDS - t0)) s] $*" >&2
}
fail() {
  echo "slurm-test: FAIL: $*" >&2
  exit 1
}
for tool in munged slurmctld slurmd sbatch scontrol scancel squeue sinfo; do
  command -v "$tool" >/dev/null || [ -x "/usr/sbin/$tool" ] ||
    fail "$tool not found: apt-get install -y slurm-wlm munge"
done
[ "$(id -u)" = 0 ] || fail "run as root: the test starts munged, slurmctld and slurmd"
PATH=$PATH:/usr/sbin

step "building shutter (release)"
cargo build --release --quiet
shutter=$root/target/release/shutter

# Stop anything a previous, interrupted run left, by the pid files it wrote.
for daemon in slurmd slurmctld munged; do
  pidfile=$work/run/$daemon.pid
  if [ -f "$pidfile" ] && pid=$(cat "$pidfile") && [ "$(cat "/proc/$pid/comm" 2>/dev/null)" = "$daemon" ]; then
    kill "$pid" 2>/dev/null || true
    sleep 1
  fi
done
rm -rf "$work"
mkdir -p "$work"/{etc,munge,run,state,spool,log}
chmod 700 "$work/munge"
chmod 755 "$work/run" # munged wants its socket's folder open to all

seq=$work/seq
step "generating a sequence: pan, $SIZE, $FRAMES frames"
"$shutter" scene pan -o "$seq" --size "$SIZE" --frames "$FRAMES" --samples 4 >/dev/null

step "one local shutter blur over frames 1-$FRAMES"
"$shutter" blur --frames "1-$FRAMES" --color "$seq/color.####.exr" --depth "$seq/depth.####.exr" \
  --velocity "$seq/velocity.####.exr" --algorithm "$ALGORITHM" -o "$work/local/blur.####.exr"

# The comparison proves something only if the blur changes the frames.
"$shutter" blur --frames 2 --color "$seq/color.####.exr" --algorithm none -o "$work/none/none.####.exr"
if cmp -s "$work/none/none.0002.exr" "$work/local/blur.0002.exr"; then
  fail "--algorithm $ALGORITHM left frame 2 as it was: the comparison would prove little"
fi

# --- the cluster -------------------------------------------------------------------------
host=$(hostname -s)
cpus=$(nproc)
dd if=/dev/urandom of="$work/munge/munge.key" bs=1024 count=1 status=none
chmod 600 "$work/munge/munge.key"
cat >"$SLURM_CONF" <<EOF
# Written by scripts/farm/slurm-test.sh: one node, loopback only.
ClusterName=shuttertest
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$PORT
SlurmdPort=$((PORT + 1))
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
# cred_expire is also how long a requeued job waits before it may start again (default 120 s).
AuthInfo=socket=$work/run/munge.sock,cred_expire=10
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/run/slurmctld.pid
SlurmdPidFile=$work/run/slurmd.pid
SlurmctldLogFile=$work/log/slurmctld.log
SlurmdLogFile=$work/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
JobRequeue=1
MinJobAge=600
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus State=UNKNOWN
PartitionName=test Nodes=ALL Default=YES MaxTime=INFINITE State=UP
EOF

pids=()
teardown() {
  local rc=$?
  set +e
  if [ "${#pids[@]}" -gt 0 ]; then
    scancel --full --quiet --user="$(id -un)" 2>/dev/null
    step "stopping the cluster"
    # Reverse order: slurmd, slurmctld, then munged.
    for ((i = ${#pids[@]} - 1; i >= 0; i--)); do
      kill "${pids[i]}" 2>/dev/null
      wait "${pids[i]}" 2>/dev/null
    done
  fi
  if [ "$rc" -ne 0 ]; then
    echo "slurm-test: logs: $work/log (daemons), $work/logs (tasks)" >&2
  fi
  exit "$rc"
}
trap teardown EXIT

step "starting munged, slurmctld, slurmd (ports $PORT, $((PORT + 1)))"
munged --foreground --socket="$work/run/munge.sock" --key-file="$work/munge/munge.key" \
  --pid-file="$work/run/munged.pid" --seed-file="$work/munge/munged.seed" \
  --log-file="$work/log/munged.log" >"$work/log/munged.out" 2>&1 &
pids+=($!)
for _ in $(seq 50); do [ -S "$work/run/munge.sock" ] && break; sleep 0.1; done
[ -S "$work/run/munge.sock" ] || { cat "$work/log/munged.out" >&2; fail "munged did not start"; }
slurmctld -D -c -f "$SLURM_CONF" >"$work/log/slurmctld.out" 2>&1 &
pids+=($!)
slurmd -D -f "$SLURM_CONF" -N "$host" >"$work/log/slurmd.out" 2>&1 &
pids+=($!)
state=
for _ in $(seq 60); do
  state=$(sinfo -h -N -o %T 2>/dev/null || true)
  [ "$state" = idle ] && break
  sleep 0.5
done
[ "$state" = idle ] || {
  tail -20 "$work"/log/slurm*.log "$work"/log/*.out >&2
  fail "the node did not come up (state: '${state:-no answer}')"
}
step "cluster up: $(sinfo -h -o '%P %D node(s) %c CPUs %T')"

# --- the array -----------------------------------------------------------------------------
# What the tasks run as shutter: a wrapper that records each blur's process id (it execs
# shutter, so the id is shutter's) and makes array task 1's first attempt exit 75, as shutter
# does when another job holds a frame's lock or a write fails with an I/O error.
mkdir -p "$work/pids"
cat >"$work/shutter-test" <<EOF
#!/usr/bin/env bash
if [ "\$1" = blur ]; then
  if [ "\${SLURM_ARRAY_TASK_ID:-}" = 1 ] && [ "\${SLURM_RESTART_COUNT:-0}" = 0 ]; then
    echo "shutter-test: a transient failure, exit 75" >&2
    exit 75
  fi
  echo \$\$ >"$work/pids/\${SLURM_ARRAY_TASK_ID:-x}.\${SLURM_RESTART_COUNT:-0}"
fi
exec "$shutter" "\$@"
EOF
chmod +x "$work/shutter-test"

out=$work/farm
chunks=$("$shutter" frames "1-$FRAMES" --chunk-size "$CHUNK" --count)
[ "$chunks" -ge 4 ] || fail "need 4 chunks or more (FRAMES, CHUNK), have $chunks"
step "submitting frames 1-$FRAMES in $chunks chunks of $CHUNK (sbatch --wait)"
: >"$work/sbatch.out"
SHUTTER_BIN=$work/shutter-test SHUTTER_FRAMES=1-$FRAMES SHUTTER_CHUNK_SIZE=$CHUNK \
  SHUTTER_COLOR=$seq/color.####.exr SHUTTER_DEPTH=$seq/depth.####.exr \
  SHUTTER_VELOCITY=$seq/velocity.####.exr SHUTTER_OUTPUT=$out/blur.####.exr \
  SHUTTER_ALGORITHM=$ALGORITHM SHUTTER_LOGS=$work/logs \
  farm/slurm/submit.sh --wait --cpus-per-task=1 --chdir="$work" >"$work/sbatch.out" 2>"$work/sbatch.err" &
sbatch_pid=$!
job=
for _ in $(seq 100); do
  job=$(sed -n 's/^Submitted batch job \([0-9]*\)$/\1/p' "$work/sbatch.out")
  [ -n "$job" ] && break
  kill -0 "$sbatch_pid" 2>/dev/null || break
  sleep 0.1
done
[ -n "$job" ] || { cat "$work/sbatch.err" >&2; fail "sbatch did not submit"; }
step "array job $job submitted"

# Stops array task $1 midway, once its first frame is in place and before its last one is,
# and requeues it. $2: kill9, SIGKILL to shutter (a crash, the OOM killer: shutter leaves its
# temporary file and lock; the script exits 137), sent while a frame's temporary file is on
# disk; or scancel, Slurm's own cancel (SIGTERM to every process of the task, SIGKILL after
# KillWait; `scancel --signal=KILL` is taken as this same cancel), which shutter answers by
# removing its temporary files.
stop_midway() {
  local task=$1 how=$2 frames first last pid="" st="" done_frames
  frames=$("$shutter" frames "$("$shutter" frames "1-$FRAMES" --chunk-size "$CHUNK" --chunk "$task")" --chunk-size 1)
  first=$(printf '%s/blur.%04d.exr' "$out" "$(echo "$frames" | head -1)")
  last=$(printf '%s/blur.%04d.exr' "$out" "$(echo "$frames" | tail -1)")
  for _ in $(seq 3000); do
    [ -z "$pid" ] && [ -f "$work/pids/$task.0" ] && pid=$(cat "$work/pids/$task.0")
    if [ -n "$pid" ] && [ -e "$first" ]; then
      [ "$how" != kill9 ] && break
      compgen -G "$out/.blur.*.exr.$pid.tmp" >/dev/null && break
    fi
    kill -0 "$sbatch_pid" 2>/dev/null || break
    sleep 0.01
  done
  [ -e "$first" ] || fail "task $task never wrote its first frame"
  [ ! -e "$last" ] || fail "task $task finished before it could be stopped: raise SIZE"
  if [ "$how" = kill9 ]; then
    kill -KILL "$pid"
    # Almost always the kill lands mid-write; if so, the rerun must say it removed the file.
    if compgen -G "$out/.blur.*.exr.$pid.tmp" >/dev/null; then left_temporary+=("$task"); fi
  else
    scancel "${job}_$task"
  fi
  for _ in $(seq 300); do
    st=$(scontrol -o show job "${job}_$task" | grep -o 'JobState=[A-Z_]*' | cut -d= -f2)
    case $st in RUNNING | COMPLETING | CONFIGURING) sleep 0.1 ;; *) break ;; esac
  done
  done_frames=$(echo "$frames" | while read -r f; do
    if [ -e "$(printf '%s/blur.%04d.exr' "$out" "$f")" ]; then echo "$f"; fi
  done | wc -l)
  step "stopped task ${job}_$task ($how) after $done_frames of its $(echo "$frames" | wc -l)" \
    "frames: $st; hidden files beside the outputs: $(cd "$out" && find . -mindepth 1 -name '.*' -printf '%f ' | sort)"
  scontrol requeue "${job}_$task"
  step "requeued ${job}_$task"
}
left_temporary=()
stop_midway 0 kill9
stop_midway 2 scancel

rc=0
wait "$sbatch_pid" || rc=$?
step "sbatch --wait returned $rc"
for _ in $(seq 300); do
  [ -z "$(squeue -h -j "$job" 2>/dev/null)" ] && break
  sleep 1
done
[ -z "$(squeue -h -j "$job" 2>/dev/null)" ] || fail "array $job still queued after sbatch returned"
[ "$rc" -eq 0 ] || fail "sbatch --wait returned $rc"

report=$(scontrol -o show job "$job" | sed -n 's/.*ArrayTaskId=\([0-9]*\) .*JobState=\([A-Z_]*\) .*Restarts=\([0-9]*\) .*ExitCode=\([0-9:]*\) .*/\1 \2 restarts=\3 exit=\4/p' | sort -n)
echo "slurm-test: tasks:"$'\n'"$report" >&2
[ "$(echo "$report" | grep -c ' COMPLETED ')" -eq "$chunks" ] || fail "not every task COMPLETED"
for task in 0 1 2; do
  echo "$report" | grep -q "^$task COMPLETED restarts=1 " ||
    fail "task $task should have completed after one restart"
done
grep -q 'transient failure; requeueing' "$work/logs/${job}_1.log" ||
  fail "task 1's log does not show the requeue"
for task in "${left_temporary[@]}"; do
  grep -q 'removed 1 temporary file that a stopped run left' "$work/logs/${job}_$task.log" ||
    fail "task $task's rerun did not remove the temporary file its killed run left"
done

# --- the outputs ---------------------------------------------------------------------------
local_list=$(cd "$work/local" && find . -mindepth 1 | sort)
farm_list=$(cd "$out" && find . -mindepth 1 | sort)
[ "$local_list" = "$farm_list" ] ||
  fail "the farm's files differ from the local run's:"$'\n'"$(diff <(echo "$local_list") <(echo "$farm_list"))"
for f in "$work"/local/*; do
  cmp "$f" "$out/${f##*/}" || fail "${f##*/} differs from the local run's"
done
step "$FRAMES outputs byte-identical to the local run, no stray files"
echo "slurm-test: PASS in $((SECONDS - t0)) s" >&2
