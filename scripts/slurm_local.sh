#!/usr/bin/env bash
# A throwaway single-node SLURM on this machine, for `make slurm-check` (not CI).
#   scripts/slurm_local.sh start DIR   installs Debian's packages if missing, starts munged,
#                                      slurmctld and slurmd with their config, state and logs
#                                      in DIR; prints the `export SLURM_CONF=...` to use
#   scripts/slurm_local.sh stop DIR    stops exactly the daemons that `start DIR` started
# Everything lives in DIR (its own munge socket, ports 16817/16818): a system SLURM or munge,
# if any, is neither used nor touched. Config that works without cgroups or a database:
# proctrack/linuxproc, task/none, select/cons_tres, one partition, daemons started directly.
set -euo pipefail

cmd=${1:?usage: slurm_local.sh start|stop DIR}
dir=${2:?usage: slurm_local.sh start|stop DIR}
# Partition time limit in minutes: what `timeout_min` is checked against.
max_time=${SLURM_MAX_TIME:-60}

stop() {
    # Reverse order; only the pids recorded by `start` in DIR.
    for name in slurmd slurmctld munged; do
        pidfile="$dir/$name.pid"
        [[ -f $pidfile ]] || continue
        pid=$(cat "$pidfile")
        if kill "$pid" 2>/dev/null; then
            for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
        fi
        rm -f "$pidfile"
    done
}

start() {
    if ! command -v slurmctld >/dev/null || ! command -v slurmd >/dev/null \
        || ! command -v sbatch >/dev/null || ! command -v munged >/dev/null; then
        echo "slurm_local: installing Debian's slurmctld, slurmd, slurm-client and munge"
        apt-get update -qq
        DEBIAN_FRONTEND=noninteractive apt-get install -y -qq slurmctld slurmd slurm-client munge >/dev/null
    fi
    mkdir -p "$dir/state" "$dir/spool" "$dir/munge"
    chmod 700 "$dir/munge"
    local key=/etc/munge/munge.key
    if [[ ! -s $key ]]; then  # the package normally creates it
        mkdir -p /etc/munge && dd if=/dev/urandom of=$key bs=1 count=1024 status=none && chmod 400 $key
    fi
    local host mem cpus
    host=$(hostname -s)
    cpus=$(nproc)
    # Leave 1 GB to the system; what `mem_gb` above it is refused against.
    mem=$(( $(slurmd -C | sed -n 's/.*RealMemory=\([0-9]*\).*/\1/p') - 1024 ))
    cat >"$dir/slurm.conf" <<EOF
ClusterName=local
SlurmctldHost=$host
SlurmctldPort=16817
SlurmdPort=16818
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$dir/munge/munge.socket
CredType=cred/munge
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/slurmctld.log
SlurmdLogFile=$dir/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
SchedulerType=sched/backfill
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
ReturnToService=2
SlurmctldTimeout=30
SlurmdTimeout=30
MinJobAge=300
NodeName=$host CPUs=$cpus RealMemory=$mem State=UNKNOWN
PartitionName=debug Nodes=$host Default=YES MaxTime=$max_time State=UP
EOF
    munged --force --socket="$dir/munge/munge.socket" --pid-file="$dir/munged.pid" \
        --log-file="$dir/munged.log" --seed-file="$dir/munge/seed" --key-file=$key
    export SLURM_CONF="$dir/slurm.conf"
    slurmctld -f "$SLURM_CONF"
    slurmd -f "$SLURM_CONF"
    for _ in $(seq 60); do
        if sinfo -h -o %T 2>/dev/null | grep -qx idle; then
            echo "export SLURM_CONF=$SLURM_CONF"
            return 0
        fi
        sleep 1
    done
    echo "slurm_local: the node did not come up; logs in $dir" >&2
    sinfo >&2 || true
    return 1
}

case $cmd in
    start) start ;;
    stop) stop ;;
    *) echo "usage: slurm_local.sh start|stop DIR" >&2; exit 2 ;;
esac
