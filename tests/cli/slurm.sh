#!/usr/bin/env bash
# The Slurm recipe (cmake/slurm/) on a real single-node Slurm started here: munged, slurmctld and slurmd on this
# host with a scratch configuration, an 8-task array of a stress matrix submitted by cmake/slurm/submit.sh with its
# dependent merge, and the merged outputs compared with `afb stress` in one process (equal but for timings). The
# daemons are stopped by their process ids at the end. Needs root and Debian's slurm-wlm and munge
# (cmake/install-deps.sh); run by .ci/run, and on demand:
#   tests/cli/slurm.sh build/dev/bin/afb [SCRATCH]
set -euo pipefail
afb="$(realpath "$1")"
src="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
scratch="$(realpath -m "${2:-$(mktemp -d /tmp/afb-slurm.XXXXXX)}")"
. "$src/tests/cli/batch-lib.sh"
for tool in munged mungekey slurmctld slurmd sbatch sinfo; do
  command -v $tool > /dev/null || fail "$tool not found (cmake/install-deps.sh installs slurm-wlm and munge)"
done
[ "$(id -u)" -eq 0 ] || fail "the daemons need root"
rm -rf "$scratch"
mkdir -p "$scratch"/{munge,state,spool,log}
chmod 755 "$scratch" # munged (the munge user) reaches its socket and key through it
host="$(hostname -s)"
pids=()
stop() {
  local p
  for p in "${pids[@]}"; do kill "$p" 2> /dev/null || true; done
  for p in "${pids[@]}"; do wait "$p" 2> /dev/null || true; done
}
trap stop EXIT

# munge: a key of its own and a socket in the scratch folder, run as the munge user.
mungekey -c -k "$scratch/munge/munge.key" > /dev/null 2>&1 || mungekey -c -f -k "$scratch/munge/munge.key"
chown -R munge: "$scratch/munge"
chmod 755 "$scratch/munge"
chmod 400 "$scratch/munge/munge.key"
runuser -u munge -- munged --foreground --force --key-file="$scratch/munge/munge.key" --socket="$scratch/munge/socket" \
  --pid-file="$scratch/munge/munged.pid" --log-file="$scratch/munge/munged.log" \
  --seed-file="$scratch/munge/seed" > "$scratch/log/munged.out" 2>&1 &
pids+=($!)

# Ports of their own, so that another Slurm on the machine is left alone.
port=$((20000 + RANDOM % 20000))
cat > "$scratch/slurm.conf" << EOF
ClusterName=afbtest
SlurmctldHost=$host
SlurmctldPort=$port
SlurmdPort=$((port + 1))
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$scratch/munge/socket
CredType=cred/munge
StateSaveLocation=$scratch/state
SlurmdSpoolDir=$scratch/spool
SlurmctldPidFile=$scratch/slurmctld.pid
SlurmdPidFile=$scratch/slurmd.pid
SlurmctldLogFile=$scratch/log/slurmctld.log
SlurmdLogFile=$scratch/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
JobCompType=jobcomp/none
MpiDefault=none
ReturnToService=2
SchedulerType=sched/backfill
NodeName=$host CPUs=$(nproc) State=UNKNOWN
PartitionName=afb Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF="$scratch/slurm.conf"
for i in $(seq 50); do [ -S "$scratch/munge/socket" ] && break; sleep 0.1; done
slurmctld -D -f "$SLURM_CONF" > "$scratch/log/slurmctld.out" 2>&1 &
pids+=($!)
slurmd -D -f "$SLURM_CONF" > "$scratch/log/slurmd.out" 2>&1 &
pids+=($!)
for i in $(seq 100); do
  state="$(sinfo -h -n "$host" -o %t 2> /dev/null || true)"
  [ "$state" = "idle" ] && break
  sleep 0.3
done
[ "$state" = "idle" ] || { tail -n 20 "$scratch"/log/*; fail "the node did not come up (state '$state')"; }

# 2 scenarios x 2 methods x 2 yaws: eight runs, eight array tasks, at most two at once.
cd "$scratch"
opts=(--base "$src" --methods fast,default --scenarios tiny-bodies,chain-mass-100 --yaws 2)
"$afb" plan stress "${opts[@]}" --manifest runs.jsonl 2> /dev/null
[ "$(grep -c . runs.jsonl)" -eq 8 ] || fail "expected 8 runs"
start=$SECONDS
AFB="$afb" AFB_MAX_RUNNING=2 "$src/cmake/slurm/submit.sh" runs.jsonl results merged --wait
echo "slurm: 8 tasks and the merge in $((SECONDS - start)) s"
[ "$(ls results | grep -c '^run-.*\.json$')" -eq 8 ] || fail "expected 8 result files: $(ls results)"
"$afb" stress "${opts[@]}" --threads 2 --out one > /dev/null
same_stress one merged
echo "slurm: the merged array equals afb stress in one process (timings aside)"
