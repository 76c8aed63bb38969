#!/usr/bin/env bash
# A Slurm cluster of this one machine, for the batch's scheduler test (tests/slurm_cli.rs) and for
# trying the book's array recipe (docs/book/src/batches.md) by hand.
#
#   scripts/slurm-local.sh start DIR   installs slurm-wlm and munge with apt-get when missing (as
#                                      root, or with sudo), writes DIR/slurm.conf for this host,
#                                      starts munged, slurmctld and slurmd (state, logs and pid
#                                      files under DIR) and waits until `sinfo` shows the node
#                                      idle; prints `SLURM_CONF=DIR/slurm.conf` on stdout.
#   scripts/slurm-local.sh stop DIR    stops the daemons that `start DIR` started (by their pid
#                                      files) and nothing else.
#
# Then: `SLURM_CONF=DIR/slurm.conf sbatch ...`. Exit status 0 when the node is up; 3 with the
# reason on stderr when Slurm cannot be installed or started here (the test then skips).
set -euo pipefail

verb="${1:-}"
dir="${2:-}"
if [ -z "$verb" ] || [ -z "$dir" ]; then
    echo "usage: $0 start|stop DIR" >&2
    exit 2
fi
mkdir -p "$dir"
dir="$(cd "$dir" && pwd)"
sudo=""
if [ "$(id -u)" -ne 0 ]; then sudo="sudo -n"; fi

cannot() {
    echo "$0: $*" >&2
    exit 3
}

stop() {
    for daemon in slurmd slurmctld munged; do
        local pidfile="$dir/$daemon.pid"
        if [ -s "$pidfile" ]; then
            local pid
            pid="$(cat "$pidfile")"
            $sudo kill "$pid" 2> /dev/null || true
            # Gone before the next start reuses its ports: 10 s, then SIGKILL.
            for _ in $(seq 20); do
                $sudo kill -0 "$pid" 2> /dev/null || break
                sleep 0.5
            done
            $sudo kill -9 "$pid" 2> /dev/null || true
            rm -f "$pidfile"
        fi
    done
}

install() {
    local missing=()
    command -v slurmctld > /dev/null || missing+=(slurm-wlm)
    command -v munged > /dev/null || missing+=(munge)
    [ "${#missing[@]}" -eq 0 ] && return 0
    command -v apt-get > /dev/null || cannot "Slurm is not installed (${missing[*]}) and there is no apt-get"
    echo "$0: installing ${missing[*]}" >&2
    { $sudo apt-get update > /dev/null && $sudo apt-get install -y --no-install-recommends "${missing[@]}" > /dev/null; } \
        || cannot "could not install ${missing[*]} with apt-get (not root, or no package source)"
}

# munged with its own socket, key and state under DIR (the system's key when there is one).
start_munge() {
    local key="$dir/munge.key"
    if $sudo test -r /etc/munge/munge.key; then
        $sudo cp /etc/munge/munge.key "$key"
    else
        $sudo dd if=/dev/urandom of="$key" bs=1 count=128 2> /dev/null
    fi
    $sudo chmod 600 "$key"
    mkdir -p "$dir/munge"
    chmod 700 "$dir/munge"
    $sudo munged --force --key-file="$key" --socket="$dir/munge/munge.socket" --pid-file="$dir/munged.pid" \
        --log-file="$dir/munged.log" --seed-file="$dir/munge/munge.seed" \
        || cannot "munged did not start (see $dir/munged.log)"
}

write_conf() {
    local host cpus
    host="$(hostname -s)"
    cpus="$(nproc)"
    mkdir -p "$dir/state" "$dir/spool"
    cat > "$dir/slurm.conf" << EOF
# Written by scripts/slurm-local.sh: a cluster of this host alone.
ClusterName=skinkit-local
SlurmctldHost=$host
SlurmUser=$(id -un)
AuthType=auth/munge
AuthInfo=socket=$dir/munge/munge.socket
CredType=cred/munge
MpiDefault=none
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/slurmctld.log
SlurmdLogFile=$dir/slurmd.log
SlurmctldPort=${SLURMCTLD_PORT:-6817}
SlurmdPort=${SLURMD_PORT:-6818}
SchedulerType=sched/backfill
MinJobAge=300
NodeName=$host CPUs=$cpus State=UNKNOWN
PartitionName=local Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
}

start() {
    install
    stop
    start_munge
    write_conf
    export SLURM_CONF="$dir/slurm.conf"
    $sudo env SLURM_CONF="$SLURM_CONF" slurmctld -i || cannot "slurmctld did not start (see $dir/slurmctld.log)"
    $sudo env SLURM_CONF="$SLURM_CONF" slurmd || cannot "slurmd did not start (see $dir/slurmd.log)"
    for _ in $(seq 60); do
        if sinfo -h -N -o '%t' 2> /dev/null | grep -qx 'idle'; then
            echo "SLURM_CONF=$SLURM_CONF"
            return 0
        fi
        sleep 0.5
    done
    local state
    state="$(sinfo -h -N -o '%t %E' 2>&1 || true)"
    stop
    cannot "the node did not become idle within 30 s (sinfo: ${state:-nothing}; see $dir/slurmctld.log and $dir/slurmd.log)"
}

case "$verb" in
    start) start ;;
    stop) stop ;;
    *)
        echo "usage: $0 start|stop DIR" >&2
        exit 2
        ;;
esac
