#!/usr/bin/env bash
# A real single-node Slurm cluster (munge + slurmctld + slurmd) in a scratch folder, started without
# systemd, for tests (munge key, slurm.conf for one node, daemons in the foreground). Source this file, then
#   slurm_cluster_start DIR   # starts the daemons, exports SLURM_CONF, waits until the node is idle
#   slurm_cluster_stop        # stops them (TERM, KILL after 15 s); safe to call twice
# Needs root (the daemons run as root) and the Debian packages slurmctld, slurmd, slurm-client, munge.

slurm_cluster_pids=()  # slurmd, slurmctld, munged: stopped in this order

# slurm_cluster_start DIR: DIR must be a fresh, empty folder
slurm_cluster_start() {
  local d=$1
  # step 1: folders; munged refuses a socket folder that others cannot enter
  mkdir -p "$d"/{munge,state,spool,log}
  chmod 755 "$d" "$d/munge"

  # step 2: a fresh munge key and munged on a private socket
  mungekey --create --keyfile="$d/munge/munge.key" --force
  chmod 400 "$d/munge/munge.key"
  munged -F --key-file="$d/munge/munge.key" --socket="$d/munge/munge.socket.2" \
    --pid-file="$d/munge/munged.pid" --log-file="$d/log/munged.log" \
    --seed-file="$d/munge/munged.seed" >"$d/log/munged.out" 2>&1 &
  slurm_cluster_pids=($! "${slurm_cluster_pids[@]}")

  # step 3: slurm.conf (loopback addresses: an unresolvable host name makes sinfo hang; no cgroup
  # plugins: the freezer is not mounted here and jobs would hang)
  local host node
  host=$(hostname -s)
  node=$(slurmd -C | head -1)
  cat > "$d/slurm.conf" <<CONF
ClusterName=ci
SlurmctldHost=${host}(127.0.0.1)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$d/munge/munge.socket.2
SlurmctldPort=6817
SlurmdPort=6818
StateSaveLocation=$d/state
SlurmdSpoolDir=$d/spool
SlurmctldPidFile=$d/slurmctld.pid
SlurmdPidFile=$d/slurmd.pid
SlurmctldLogFile=$d/log/slurmctld.log
SlurmdLogFile=$d/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerType=sched/backfill
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
JobCompType=jobcomp/none
MpiDefault=none
ReturnToService=2
MinJobAge=10
MailProg=/bin/true
KillWait=5
$node NodeAddr=127.0.0.1 State=UNKNOWN
PartitionName=debug Nodes=ALL Default=YES MaxTime=INFINITE State=UP
CONF
  export SLURM_CONF=$d/slurm.conf
  slurmctld -D -i >"$d/log/slurmctld.out" 2>&1 &
  slurm_cluster_pids=($! "${slurm_cluster_pids[@]}")
  slurmd -D >"$d/log/slurmd.out" 2>&1 &
  slurm_cluster_pids=($! "${slurm_cluster_pids[@]}")

  # step 4: wait (at most 60 s) until the node reports idle
  local i state
  for ((i = 0; i < 300; i++)); do
    state=$(timeout 5 sinfo -h -N -o %t 2>/dev/null || true)
    [[ "$state" == idle ]] && return 0
    sleep 0.2
  done
  echo "slurm_cluster_start: the node did not become idle (state '${state:-none}'); logs in $d/log" >&2
  return 1
}

# slurm_cluster_stop: cancel the cluster's jobs (at most 10 s), then TERM each daemon (slurmd first,
# munged last) and KILL what is left after 15 s
slurm_cluster_stop() {
  local pid i
  if ((${#slurm_cluster_pids[@]} > 0)); then
    timeout 5 scancel --quiet --user="$(id -un)" 2>/dev/null || true
    for ((i = 0; i < 50; i++)); do
      [[ -z $(timeout 5 squeue -h -t PD,R,CG -o %i 2>/dev/null) ]] && break
      sleep 0.2
    done
  fi
  for pid in "${slurm_cluster_pids[@]}"; do
    kill -TERM "$pid" 2>/dev/null || continue
    for ((i = 0; i < 150; i++)); do
      kill -0 "$pid" 2>/dev/null || break
      sleep 0.1
    done
    kill -KILL "$pid" 2>/dev/null || true
    wait "$pid" 2>/dev/null || true
  done
  slurm_cluster_pids=()
}
