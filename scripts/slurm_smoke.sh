#!/usr/bin/env bash
# Slurm for real (issue 32): a one-node cluster on this machine runs a sweep as
# an array job through the real scheduler, and the collected table is checked.
#
#   scripts/slurm_smoke.sh [QUADCL_BINARY]
#
# 1. Installs Slurm and munge from the distribution's packages when they are
#    missing (apt-get; as root, or with sudo).
# 2. Starts munged, slurmctld and slurmd (as root, in the foreground, in the
#    background of this script) with a minimal slurm.conf written to a temporary
#    folder that also holds their keys, sockets, state, spool and logs. Their
#    ports (16817, 16818) are not Slurm's defaults, so a cluster already on this
#    machine is left alone.
# 3. Plans the 2 x 2 sweep scenes/sweep-smoke.toml (scenes/smoke.toml with two
#    mask capacities and two seeds), submits it with
#    `quadcl sweep slurm --submit`, checks that `quadcl sweep status` sees the
#    cells queued or running (squeue), waits for the array, collects it,
#    and checks the table: two groups of two finished seeds, each mean inside its
#    interval, every run's provenance naming its cell's run file. The sweep's
#    folder is named "my sweep's dir": its #SBATCH lines must carry the space and
#    the quote, and every cell's log must land in its logs/.
# 4. Stops only the daemons it started (by their process ids) and removes its folder.
set -euo pipefail
cd "$(dirname "$0")/.."
bin=$(realpath "${1:-target/debug/quadcl}")
[ -x "$bin" ] || { echo "no binary at $bin: cargo build first" >&2; exit 1; }

as_root() { if [ "$(id -u)" -eq 0 ]; then "$@"; else sudo "$@"; fi; }
missing=()
command -v munged >/dev/null 2>&1 || missing+=(munge)
for tool in slurmctld slurmd sbatch squeue; do
  command -v "$tool" >/dev/null 2>&1 || { missing+=(slurm-wlm); break; }
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "installing ${missing[*]} with apt-get"
  as_root apt-get update -qq
  as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${missing[@]}" >/dev/null
fi
# The daemons run as root (and the array's tasks as the submitting user).
[ "$(id -u)" -eq 0 ] || exec sudo "$0" "$bin"

tmp=$(mktemp -d /tmp/quadcl-slurm.XXXXXX)
chmod 755 "$tmp"
pids=()
job=""
stop() {
  local rc=$?
  if [ -n "$job" ]; then scancel "$job" 2>/dev/null || true; fi
  # Last started, first stopped; only the daemons this script started.
  for ((i = ${#pids[@]} - 1; i >= 0; i--)); do
    kill "${pids[$i]}" 2>/dev/null || true
    wait "${pids[$i]}" 2>/dev/null || true
  done
  if [ $rc -ne 0 ]; then
    for log in "$tmp"/*.log "$tmp"/*.out "$tmp"/*/logs/*.log; do
      [ -f "$log" ] && { echo "--- $log"; tail -n 20 "$log"; }
    done
  fi
  rm -rf "$tmp"
  exit $rc
}
trap stop EXIT

# munge: a fresh key, its socket and files in the folder.
mkdir -p "$tmp/munge"
dd if=/dev/urandom of="$tmp/munge/munge.key" bs=1024 count=1 status=none
chmod 711 "$tmp/munge"
chmod 400 "$tmp/munge/munge.key"
socket="$tmp/munge/munge.socket"
munged -F --force --socket="$socket" --key-file="$tmp/munge/munge.key" --pid-file="$tmp/munge/munged.pid" \
  --log-file="$tmp/munged.log" --seed-file="$tmp/munge/munged.seed" >>"$tmp/munged.out" 2>&1 &
pids+=($!)
for _ in $(seq 100); do [ -S "$socket" ] && break; sleep 0.1; done
[ -S "$socket" ] || { echo "munged did not start" >&2; exit 1; }

host=$(hostname -s)
cpus=$(nproc)
# RealMemory (MB) below what is free now.
memory=$(awk '/MemAvailable/ { printf "%d", $2 / 1024 / 2 }' /proc/meminfo)
mkdir -p "$tmp/state" "$tmp/spool"
export SLURM_CONF="$tmp/slurm.conf"
cat > "$SLURM_CONF" <<CONF
ClusterName=quadcl-smoke
SlurmctldHost=$host
SlurmctldPort=16817
SlurmdPort=16818
AuthType=auth/munge
AuthInfo=socket=$socket
CredType=cred/munge
SlurmUser=root
SlurmdUser=root
StateSaveLocation=$tmp/state
SlurmdSpoolDir=$tmp/spool
SlurmctldPidFile=$tmp/slurmctld.pid
SlurmdPidFile=$tmp/slurmd.pid
SlurmctldLogFile=$tmp/slurmctld.log
SlurmdLogFile=$tmp/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/backfill
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
JobCompType=jobcomp/none
MpiDefault=none
ReturnToService=2
NodeName=$host CPUs=$cpus RealMemory=$memory State=UNKNOWN
PartitionName=smoke Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
slurmctld -D -i -f "$SLURM_CONF" >>"$tmp/slurmctld.log" 2>&1 &
pids+=($!)
slurmd -D -f "$SLURM_CONF" -N "$host" >>"$tmp/slurmd.log" 2>&1 &
pids+=($!)
for _ in $(seq 120); do
  state=$(sinfo -h -n "$host" -o %T 2>/dev/null || true)
  [ "$state" = idle ] && break
  sleep 0.5
done
[ "$state" = idle ] || { echo "the node did not come up (sinfo: ${state:-no answer})" >&2; exit 1; }
echo "a one-node cluster on $host: $cpus CPUs, ${memory} MB"

# The sweep's folder holds a space and a single quote: its #SBATCH --output must reach sbatch's
# directive reader as one path, and the logs must land in it (sweep status reads them there).
sweep="$tmp/my sweep's dir"
"$bin" sweep plan scenes/sweep-smoke.toml --out "$sweep"
submitted=$("$bin" sweep slurm "$sweep" --cpus-per-task 1 --time 00:20:00 --submit)
echo "$submitted"
job=$(sed -n 's/^submitted as job \([0-9]*\).*/\1/p' <<<"$submitted")
[ -n "$job" ] || { echo "no job id in: $submitted" >&2; exit 1; }
# Right after submission every cell is in the scheduler's hands: quadcl sweep status asks squeue.
states=$("$bin" sweep status "$sweep" --json | python3 -c 'import json, sys; print(" ".join(c["state"] for c in json.load(sys.stdin)))')
echo "cells as submitted: $states"
for s in $states; do
  case $s in queued | running | finished) ;; *) echo "cell $s right after submission: squeue not read?" >&2; exit 1 ;; esac
done
start=$(date +%s)
while [ -n "$(squeue -h -j "$job" 2>/dev/null)" ]; do
  [ $(( $(date +%s) - start )) -lt 1200 ] || { echo "the array did not finish in 20 minutes" >&2; exit 1; }
  sleep 2
done
job=""
echo "the array ran in $(( $(date +%s) - start )) s"
"$bin" sweep status "$sweep"
"$bin" sweep collect "$sweep"
python3 - "$sweep" <<'PY'
import json, sys
d = sys.argv[1]
table = json.load(open(f"{d}/collected.json"))
plan = json.load(open(f"{d}/sweep.json"))
names = [g["name"] for g in table["groups"]]
assert names == ["capacity=0.2", "capacity=0.3"], names
for g in table["groups"]:
    assert (g["planned"], g["finished"]) == (2, 2), g
    e = g["measures"]["average_performance"]
    assert e["n"] == 2 and e["low"] <= e["mean"] <= e["high"], e
    assert g["measures"]["forgetting"]["mean"] == 0.0, g["measures"]["forgetting"]
    assert [c["seed"] for c in g["cells"]] == [1, 2], g["cells"]
import os
for c in plan["cells"]:
    log = f"{d}/logs/{c['index']}.log"
    assert os.path.getsize(log) > 0, f"no log at {log}: the #SBATCH --output did not reach the sweep's folder"
    m = json.load(open(f"{d}/{c['run']}/metrics.json"))
    assert m["provenance"]["run_file_sha256"] == c["run_file_sha256"], c["index"]
    assert m["provenance"]["threads"] == 1, m["provenance"]
print(f"slurm smoke: the table of 2 x 2 cells in {d!r} is complete and consistent, every log in its logs/")
PY
