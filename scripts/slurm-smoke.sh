#!/usr/bin/env bash
# Single-node Slurm smoke test of the README's job-array recipe, on a real Slurm:
#   1. stands up munge and a one-node Slurm cluster (slurmctld + slurmd, as root, state in a
#      temporary directory; Debian's slurm-wlm and munge, installed if missing);
#   2. submits the README's job array (`isotrack sweep ... --shard $SLURM_ARRAY_TASK_ID/N --resume`)
#      for a small sweep;
#   3. waits until one array task has written part of its shard, then requeues it (Slurm kills it
#      mid-run and runs it again; `--resume` keeps its finished rows);
#   4. merges the shards with `isotrack merge` and checks that the merged results.csv is
#      byte-identical to the same sweep run in one process.
# Run by .ci/run. Needs root (the daemons) and about a minute once the packages are installed.
set -euo pipefail
cd "$(dirname "$0")/.."
repo=$PWD

if [ "$(id -u)" -ne 0 ]; then
  echo "slurm-smoke: needs root (it starts munged, slurmctld and slurmd)" >&2
  exit 77
fi
if ! command -v slurmctld >/dev/null 2>&1 || ! command -v munged >/dev/null 2>&1; then
  apt-get update
  DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends slurm-wlm munge
fi
[ -x target/release/isotrack ] || cargo build --release --locked -p isotrack-cli
isotrack=$repo/target/release/isotrack

work=$(mktemp -d /tmp/isotrack-slurm.XXXXXX)
host=$(hostname -s)
cpus=$(nproc)
shards=4

ok=""
cleanup() {
  set +e
  pids=""
  for d in slurmctld slurmd munged; do
    [ -f "$work/$d.pid" ] && pids="$pids $(cat "$work/$d.pid")"
  done
  # shellcheck disable=SC2086 # a list of pids
  [ -n "$pids" ] && kill $pids 2>/dev/null
  for _ in $(seq 50); do
    alive=""
    for p in $pids; do kill -0 "$p" 2>/dev/null && alive=1; done
    [ -z "$alive" ] && break
    sleep 0.2
  done
  # Kept for a look when the test failed.
  if [ -n "$ok" ]; then
    sleep 1
    rm -rf "$work" 2>/dev/null || { sleep 2; rm -rf "$work"; }
  fi
}
trap cleanup EXIT
fail() {
  echo "slurm-smoke: FAILED: $*" >&2
  for log in slurmctld.log slurmd.log; do
    echo "--- $log (last lines)" >&2
    tail -n 20 "$work/$log" >&2 2>/dev/null || true
  done
  exit 1
}

# --- munge: its own key, socket and pid file in the work directory.
mkdir -p "$work/munge"
chmod 700 "$work/munge"
dd if=/dev/urandom of="$work/munge/munge.key" bs=1024 count=1 status=none
chmod 400 "$work/munge/munge.key"
munged --force --key-file="$work/munge/munge.key" --socket="$work/munge/munge.socket" \
  --pid-file="$work/munged.pid" --log-file="$work/munged.log" --seed-file="$work/munge/seed"

# --- Slurm: one node, root daemons, no cgroups (a container has none to give).
mkdir -p "$work/state" "$work/spool"
cat > "$work/slurm.conf" <<EOF
ClusterName=isotrack-smoke
SlurmctldHost=$host
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$work/munge/munge.socket
CredType=cred/munge
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/slurmctld.log
SlurmdLogFile=$work/slurmd.log
SlurmctldPort=16817
SlurmdPort=16818
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/backfill
MpiDefault=none
ReturnToService=2
JobRequeue=1
NodeName=$host CPUs=$cpus State=UNKNOWN
PartitionName=smoke Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF=$work/slurm.conf
slurmctld -f "$SLURM_CONF"
slurmd -f "$SLURM_CONF"
for _ in $(seq 60); do
  sinfo -h -o %T 2>/dev/null | grep -qE '^(idle|mixed|allocated)' && break
  sleep 1
done
sinfo -h -o %T | grep -qE '^(idle|mixed|allocated)' || fail "the node did not come up: $(sinfo 2>&1)"

# --- A small sweep: 240 runs of the default scenario (about 3 s of work per shard).
mkdir -p "$work/sweeps" "$work/out"
cp "$repo/scenarios/paper-fig2b-circular.toml" "$work/sweeps/scenario.toml"
cat > "$work/sweeps/smoke.toml" <<'EOF'
scenario = "scenario.toml"

[grid]
controller.kp = [5.0, 10.0, 20.0]

[random]
runs = 80
seed = 7
initial.x_m = { uniform = [8.0, 14.0] }
initial.heading_rad = { uniform = [-3.141592653589793, 3.141592653589793] }
EOF

# --- The README's job array, for this sweep and $shards shards.
cat > "$work/job.sh" <<EOF
#!/bin/bash
#SBATCH --job-name=isotrack-sweep
#SBATCH --array=1-$shards
#SBATCH --cpus-per-task=1
#SBATCH --requeue
#SBATCH --open-mode=append
#SBATCH --output=$work/out/slurm-%A_%a.log
$isotrack sweep $work/sweeps/smoke.toml --out $work/out/shard-\$SLURM_ARRAY_TASK_ID \\
    --shard \$SLURM_ARRAY_TASK_ID/$shards --threads \$SLURM_CPUS_PER_TASK --resume
EOF
job=$(sbatch --parsable "$work/job.sh") || fail "sbatch refused the job"
echo "slurm-smoke: submitted array job $job ($shards tasks)"

# --- Kill task 1 mid-run: once its shard has some rows but not all, requeue it.
per_shard=$((240 / shards))
victim="${job}_1"
partial=""
for _ in $(seq 2400); do  # up to 2 min: a loaded machine starts the task late
  f="$work/out/shard-1/results.csv"
  if [ -f "$f" ]; then
    rows=$(($(wc -l < "$f") - 1))
    if [ "$rows" -ge 3 ] && [ "$rows" -lt "$per_shard" ]; then
      scontrol requeue "$victim" && partial=$rows
      break
    fi
    [ "$rows" -ge "$per_shard" ] && break
  fi
  sleep 0.05
done
[ -n "$partial" ] || fail "could not requeue task 1 mid-run (its shard finished first or never started)"
echo "slurm-smoke: requeued $victim with $partial of $per_shard rows written"

# --- Slurm holds a requeued job back (BeginTime); let it start now.
for _ in $(seq 100); do
  state=$(squeue -h -j "$victim" -o %T 2>/dev/null || true)
  [ "$state" = "PENDING" ] && scontrol update JobId="$victim" StartTime=now 2>/dev/null && break
  sleep 0.2
done

# --- Wait for the array to finish.
for _ in $(seq 2400); do  # up to 2 min: a loaded machine starts the task late
  [ -z "$(squeue -h -j "$job" 2>/dev/null)" ] && break
  sleep 1
done
[ -z "$(squeue -h -j "$job")" ] || fail "the array job did not finish: $(squeue -j "$job")"
echo "slurm-smoke: all tasks done"
# The requeued task resumed: its second run kept the rows of the first (the log is appended).
last=$(grep -E "runs \([0-9]+ new\) of shard 1/$shards" "$work/out/slurm-${job}_1.log" | tail -n 1 || true)
new=$(echo "$last" | sed -E 's/.*\(([0-9]+) new\).*/\1/')
[ -n "$new" ] && [ "$new" -lt "$per_shard" ] || fail "task 1 did not resume its shard: '$last'"

# --- Merge, and compare with the same sweep in one process.
"$isotrack" merge "$work"/out/shard-* --out "$work/out/merged"
"$isotrack" sweep "$work/sweeps/smoke.toml" --out "$work/single" >/dev/null 2>&1
rows=$(($(wc -l < "$work/out/merged/results.csv") - 1))
[ "$rows" -eq 240 ] || fail "merged results.csv has $rows runs, expected 240"
cmp "$work/out/merged/results.csv" "$work/single/results.csv" \
  || fail "merged results.csv differs from the single-process sweep"
echo "slurm-smoke: OK: $shards-task array, task 1 killed and requeued at $partial/$per_shard rows and resumed ($new new runs), merged results.csv byte-identical to one process (240 runs)"
ok=1
