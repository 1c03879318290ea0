#!/usr/bin/env bash
# A real Slurm cluster in the test suite: starts munged, slurmctld and slurmd on localhost with
# a generated configuration in a private temporary folder (nothing in /etc is read or written),
# runs a small sweep as a job array through scenarios/slurm/sweep.sbatch (the README's recipe),
# merges the shards, and checks that every per-run record equals the same sweep run locally.
# Every daemon is stopped by its own PID on exit, pass or fail.
# usage: slurm_sweep_test.sh HPA_BIN SCENARIOS_DIR OUT_DIR
# Needs root and Debian's slurm-wlm and munge (ci/setup.sh installs them).
# Env: HPA_SLURM_CTLD_PORT (6817), HPA_SLURM_SLURMD_PORT (6818), HPA_SLURM_TIMEOUT_S (300).
set -euo pipefail
hpa=$(realpath "$1"); scen=$(realpath "$2"); out=$3
# shellcheck source=cli_test_lib.sh
source "$(dirname "$0")/cli_test_lib.sh"
ctld_port=${HPA_SLURM_CTLD_PORT:-6817}
slurmd_port=${HPA_SLURM_SLURMD_PORT:-6818}
timeout_s=${HPA_SLURM_TIMEOUT_S:-300}
shards=3

say() { echo "[slurm_sweep_test] $*"; }
die() { echo "[slurm_sweep_test] FAIL: $*" >&2; exit 1; }

[ "$(id -u)" = 0 ] || die "must run as root (the daemons run as root here)"
for b in munged mungekey munge unmunge slurmctld slurmd sbatch squeue sinfo scontrol scancel; do
  command -v "$b" > /dev/null || die "$b not found: install slurm-wlm and munge (ci/setup.sh)"
done

rm -rf "$out"; mkdir -p "$out"
out=$(realpath "$out")
work=$(mktemp -d -t hpa-slurm.XXXXXX)
chmod 755 "$work"  # munged wants every folder above its socket to be searchable by all
mkdir -p "$work"/{munge,state,spool,log}
export SLURM_CONF=$work/slurm.conf
munge_socket=$work/munge/munge.sock
daemon_pids=()
job_id=

teardown() {
  local status=$? i pid
  set +e
  trap - EXIT INT TERM
  [ -n "$job_id" ] && scancel "$job_id" 2> /dev/null
  # slurmd, slurmctld, munged: reverse start order, each by its PID, then reaped
  for ((i = ${#daemon_pids[@]} - 1; i >= 0; i--)); do
    pid=${daemon_pids[i]}
    kill -TERM "$pid" 2> /dev/null
    for _ in $(seq 1 100); do kill -0 "$pid" 2> /dev/null || break; sleep 0.1; done
    kill -0 "$pid" 2> /dev/null && kill -KILL "$pid"
    wait "$pid" 2> /dev/null
  done
  if [ "$status" != 0 ]; then
    for f in "$work"/log/*; do [ -s "$f" ] && { echo "---- $f"; tail -n 20 "$f"; }; done >&2
  fi
  rm -rf "$work"
  say "$([ "$status" = 0 ] && echo PASS || echo "FAIL (exit $status)")"
  exit "$status"
}
trap teardown EXIT
trap 'exit 130' INT
trap 'exit 143' TERM

port_in_use() { (exec 3<> "/dev/tcp/127.0.0.1/$1") 2> /dev/null; }
for p in "$ctld_port" "$slurmd_port"; do
  port_in_use "$p" && die "port $p is in use (another Slurm?); set HPA_SLURM_*_PORT"
done

# munge: its own key, socket, pid and seed files in the work folder
mungekey --create --keyfile="$work/munge/munge.key"
chmod 600 "$work/munge/munge.key"
munged --foreground --socket="$munge_socket" --key-file="$work/munge/munge.key" \
  --origin=127.0.0.1 --pid-file="$work/munge/munged.pid" --seed-file="$work/munge/munged.seed" \
  < /dev/null > "$work/log/munged.log" 2>&1 &
daemon_pids+=($!)
for _ in $(seq 1 50); do
  munge -n -S "$munge_socket" 2> /dev/null | unmunge -S "$munge_socket" > /dev/null 2>&1 && break
  sleep 0.1
done
munge -n -S "$munge_socket" | unmunge -S "$munge_socket" > /dev/null || die "munge round trip failed"

# slurm.conf: the node line is slurmd's own view of the hardware (a larger RealMemory drains it)
node=$(hostname -s)
hardware=$(slurmd -C | head -n 1 | sed -e 's/^NodeName=[^ ]* //')
cat > "$SLURM_CONF" << EOF
ClusterName=hpatest
SlurmctldHost=$node(127.0.0.1)
SlurmUser=root
SlurmdUser=root
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$munge_socket
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/log/slurmctld.log
SlurmdLogFile=$work/log/slurmd.log
MailProg=/bin/true
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
MpiDefault=none
SwitchType=switch/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
JobCompType=jobcomp/none
ReturnToService=2
NodeName=$node NodeAddr=127.0.0.1 $hardware State=UNKNOWN
PartitionName=debug Nodes=$node Default=YES MaxTime=INFINITE State=UP
EOF
# daemons as direct children of this shell, so teardown can kill and reap them by PID
slurmctld -D -f "$SLURM_CONF" < /dev/null > "$work/log/slurmctld.out" 2>&1 &
daemon_pids+=($!)
slurmd -D -f "$SLURM_CONF" -N "$node" < /dev/null > "$work/log/slurmd.out" 2>&1 &
daemon_pids+=($!)
state=
for _ in $(seq 1 150); do
  state=$(sinfo -h -n "$node" -o %T 2> /dev/null || true)
  [ "$state" = idle ] && break
  for pid in "${daemon_pids[@]}"; do kill -0 "$pid" 2> /dev/null || die "daemon $pid exited"; done
  sleep 0.2
done
[ "$state" = idle ] || die "node $node is '$state', expected idle"
say "cluster up: munged, slurmctld, slurmd (node $node idle)"

# a small sweep: geometric controller on ground truth, an impulse and a mass drawn per run
impulse_hover_base "$out/base.yaml" slurm_base 2.0 0.5
cat > "$out/sweep.yaml" << 'YAML'
base: base.yaml
runs: 4
seed: 11
vary:
  events.0.impulse.2: {uniform: [0.05, 0.4]}
  world.payload_mass: {normal: [0.1, 0.01]}
  controller.type: {grid: [geometric, hpa_mpc]}
YAML

job_id=$(sbatch --parsable --array=1-$shards --chdir="$out" -o "$out/task_%a.out" \
  -e "$out/task_%a.err" --export="ALL,HPA_BIN=$hpa,HPA_SWEEP=$out/sweep.yaml,HPA_OUT=$out/slurm" \
  "$scen/slurm/sweep.sbatch")
job_id=${job_id%%;*}
say "submitted array job $job_id (1-$shards)"
# poll: sbatch --wait backs off up to 32 s between checks
deadline=$(($(date +%s) + timeout_s))
while [ -n "$(squeue -h -j "$job_id" 2> /dev/null)" ]; do
  [ "$(date +%s)" -lt "$deadline" ] || die "job array not done after $timeout_s s"
  sleep 0.25
done
not_ok=$(scontrol -o show job "$job_id" | grep -v 'JobState=COMPLETED .*ExitCode=0:0' || true)
[ -z "$not_ok" ] || die "array tasks did not all complete with exit 0: $not_ok"
job_id=
say "array done"

"$hpa" merge "$out"/slurm/shard* --out "$out/slurm/merged" > "$out/merge.log" 2>&1 \
  || die "merge failed: $(cat "$out/merge.log")"
"$hpa" sweep "$out/sweep.yaml" --out "$out/local" --jobs 2 > "$out/local.log" 2>&1 \
  || die "local sweep failed: $(cat "$out/local.log")"

# the per-run records, timing fields aside, must be the same runs with the same results
python3 - "$out/slurm/merged/runs.jsonl" "$out/local/runs.jsonl" << 'PY'
import json, sys
timing = {"wall_time_s", "mpc_solve_ms", "render_ms", "detector_ms", "image_model_ms"}
def strip(x):
    if isinstance(x, dict):
        return {k: strip(v) for k, v in x.items() if k not in timing}
    if isinstance(x, list):
        return [strip(v) for v in x]
    return x
def records(path):
    out = {}
    with open(path) as f:
        for line in f:
            if line.strip():
                r = strip(json.loads(line))
                out[r["run"]] = r
    return out
slurm, local = records(sys.argv[1]), records(sys.argv[2])
if len(local) != 8:
    sys.exit(f"local sweep recorded {len(local)} runs, expected 8")
if sorted(slurm) != sorted(local):
    sys.exit(f"run indices differ: slurm {sorted(slurm)} local {sorted(local)}")
for k in local:
    if slurm[k] != local[k]:
        sys.exit(f"run {k} differs:\n slurm {slurm[k]}\n local {local[k]}")
print(f"[slurm_sweep_test] {len(local)} runs: Slurm job array records equal the local sweep's")
PY
for f in summary.md summary.json crash_rate.png; do
  [ -s "$out/slurm/merged/$f" ] || die "merge wrote no $f"
done
