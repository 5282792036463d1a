#!/usr/bin/env bash
# One-node Slurm cluster on localhost, for trying the pbgi farm scripts in a
# container without systemd. Run as root.
#   farm/slurm/one-node.sh [start]   install if needed, start munged/slurmctld/slurmd, wait for idle
#   farm/slurm/one-node.sh stop      stop the daemons started from this directory
#   farm/slurm/one-node.sh status    show sinfo
# State, spool, logs and pid files live in $PBGI_SLURM_DIR (default /tmp/pbgi-slurm).
# Environment: PBGI_SLURM_DIR, PBGI_SLURM_TIMEOUT (seconds to wait for idle, default 60).
set -euo pipefail

DIR=${PBGI_SLURM_DIR:-/tmp/pbgi-slurm}
TIMEOUT=${PBGI_SLURM_TIMEOUT:-60}
CONF_DIR=/etc/slurm                 # Debian's slurm binaries read /etc/slurm/slurm.conf
CONF=$CONF_DIR/slurm.conf
NODE=$(hostname -s)

die() { echo "one-node.sh: $*" >&2; exit 1; }
[ "$(id -u)" = 0 ] || die "must run as root"

log_tails() {
    for f in "$DIR"/log/slurmctld.log "$DIR"/log/slurmd.log /var/log/munge/munged.log; do
        [ -f "$f" ] && { echo "---- tail $f" >&2; tail -n 20 "$f" >&2; }
    done
}

pid_alive() { # pidfile
    [ -s "$1" ] && kill -0 "$(cat "$1")" 2>/dev/null
}

install_pkgs() {
    if ! command -v slurmctld >/dev/null || ! command -v slurmd >/dev/null \
       || ! command -v sbatch >/dev/null || ! command -v munged >/dev/null; then
        echo "installing slurm-wlm and munge ..."
        export DEBIAN_FRONTEND=noninteractive
        apt-get update -qq
        apt-get install -y -qq --no-install-recommends slurm-wlm munge >/dev/null
    fi
}

start_munge() {
    if [ ! -s /etc/munge/munge.key ]; then
        echo "creating munge key"
        mkdir -p /etc/munge
        if command -v mungekey >/dev/null; then
            mungekey --create --keyfile=/etc/munge/munge.key --force
        else
            dd if=/dev/urandom of=/etc/munge/munge.key bs=1024 count=1 status=none
        fi
    fi
    id munge >/dev/null 2>&1 && chown munge:munge /etc/munge/munge.key
    chmod 400 /etc/munge/munge.key
    mkdir -p /run/munge /var/log/munge /var/lib/munge
    id munge >/dev/null 2>&1 && chown munge:munge /run/munge /var/log/munge /var/lib/munge
    chmod 755 /run/munge
    if munge -n 2>/dev/null | unmunge >/dev/null 2>&1; then
        return 0                        # already running and working
    fi
    # stale socket/pid from a dead munged
    rm -f /run/munge/munge.socket.2 /run/munge/munge.socket.2.lock /run/munge/munged.pid
    if id munge >/dev/null 2>&1; then
        runuser -u munge -- munged
    else
        munged --force
    fi
    for _ in $(seq 50); do
        munge -n 2>/dev/null | unmunge >/dev/null 2>&1 && return 0
        sleep 0.1
    done
    log_tails; die "munged did not start"
}

write_conf() {
    local topo mem_mb
    # CPUs/sockets/cores/threads as slurmd itself sees them (avoids a
    # "reconfigured socket/core boundaries" mismatch); 90 % of RAM.
    topo=$(slurmd -C | head -n1 | grep -o 'CPUs=.*ThreadsPerCore=[0-9]*') \
        || topo="CPUs=$(nproc)"
    mem_mb=$(awk '/MemTotal/ {printf "%d", $2/1024*0.9}' /proc/meminfo)
    mkdir -p "$DIR"/{state,spool,log,run} "$CONF_DIR"
    local new
    new=$(cat <<CONF
# Written by farm/slurm/one-node.sh; a one-node test cluster.
ClusterName=pbgi
SlurmctldHost=$NODE(127.0.0.1)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
StateSaveLocation=$DIR/state
SlurmdSpoolDir=$DIR/spool
SlurmctldLogFile=$DIR/log/slurmctld.log
SlurmdLogFile=$DIR/log/slurmd.log
SlurmctldPidFile=$DIR/run/slurmctld.pid
SlurmdPidFile=$DIR/run/slurmd.pid
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
MaxJobCount=100000
MaxArraySize=100001
SlurmdTimeout=300
MpiDefault=none
NodeName=$NODE NodeAddr=127.0.0.1 $topo RealMemory=$mem_mb State=UNKNOWN
PartitionName=main Nodes=$NODE Default=YES MaxTime=INFINITE State=UP
CONF
)
    if [ ! -f "$CONF" ] || [ "$(cat "$CONF")" != "$new" ]; then
        printf '%s\n' "$new" > "$CONF"
        CONF_CHANGED=1
    fi
    # No cgroup.conf: Slurm 22.05 (bookworm) has no CgroupPlugin=disabled
    # (slurmd refuses to start with it); its default, autodetect, loads even
    # in a container, and with proctrack/linuxproc + task/none nothing is
    # ever written to the cgroup tree. Remove one left by an older version
    # of this script.
    if [ -f "$CONF_DIR/cgroup.conf" ] && grep -q '^CgroupPlugin=disabled' "$CONF_DIR/cgroup.conf"; then
        rm -f "$CONF_DIR/cgroup.conf"
    fi
}

node_state() { sinfo -h -N -n "$NODE" -o '%T' 2>/dev/null | head -n1; }

start() {
    install_pkgs
    start_munge
    CONF_CHANGED=0
    write_conf
    if [ "$CONF_CHANGED" = 1 ]; then   # restart what runs on an older config
        stop_one slurmd "$DIR/run/slurmd.pid"
        stop_one slurmctld "$DIR/run/slurmctld.pid"
    fi
    if ! pid_alive "$DIR/run/slurmctld.pid"; then
        echo "starting slurmctld"
        slurmctld || { log_tails; die "slurmctld failed to start"; }
    fi
    if ! pid_alive "$DIR/run/slurmd.pid"; then
        echo "starting slurmd"
        slurmd || { log_tails; die "slurmd failed to start"; }
    fi
    local t0=$SECONDS st=""
    while :; do
        st=$(node_state)
        case "$st" in
            idle*|mixed*|allocated*|completing*) break ;;
            down*|drain*)
                scontrol update NodeName="$NODE" State=RESUME >/dev/null 2>&1 || true ;;
        esac
        if (( SECONDS - t0 >= TIMEOUT )); then
            echo "node $NODE is '${st:-no answer}' after ${TIMEOUT}s" >&2
            sinfo >&2 || true
            log_tails; die "cluster did not come up"
        fi
        sleep 0.5
    done
    echo "slurm $(sinfo -V | awk '{print $2}') up: node $NODE $st (state in $DIR)"
}

stop_one() { # name pidfile
    if pid_alive "$2"; then
        local pid; pid=$(cat "$2")
        kill "$pid"
        for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
        kill -0 "$pid" 2>/dev/null && kill -9 "$pid"
        echo "stopped $1 ($pid)"
    fi
    rm -f "$2"
}

stop() {
    stop_one slurmd "$DIR/run/slurmd.pid"
    stop_one slurmctld "$DIR/run/slurmctld.pid"
    if [ -s /run/munge/munged.pid ] && kill -0 "$(cat /run/munge/munged.pid)" 2>/dev/null; then
        stop_one munged /run/munge/munged.pid
    fi
}

case "${1:-start}" in
    start) start ;;
    stop) stop ;;
    status) sinfo; squeue ;;
    *) die "usage: $0 [start|stop|status]" ;;
esac
