#!/usr/bin/env bash
# local-cluster.sh - a private one-node Slurm for tests and CI.
#
# The project's job-array recipe is tested against a real Slurm, not a mock.
# This script brings up munged, slurmctld and slurmd for this host on
# localhost, with every file (config, munge key and socket, state, spool,
# logs, pid files) inside one folder DIR. It never reads or writes
# /etc/slurm or /etc/munge and never touches system services, so it can run
# beside (or instead of) a system Slurm and is thrown away with DIR.
#
# Usage:
#   eval "$(scripts/slurm/local-cluster.sh start DIR)"   # prints: export SLURM_CONF=DIR/slurm.conf
#   sbatch --wait --array=0-3 --wrap '...'                # etc.
#   scripts/slurm/local-cluster.sh stop DIR               # idempotent
#
# Needs root (slurmd runs job steps as the submitting user) and the Debian
# packages slurmctld slurmd slurm-client munge (tested with Slurm 22.05).
# No accounting storage: sacct does not work; a finished job's state is in
# `scontrol show job` for MinJobAge seconds and for good in DIR/log/jobcomp.log.
set -euo pipefail

prog=${0##*/}

die() {
    echo "$prog: $*" >&2
    exit 1
}

usage() {
    echo "usage: $prog start DIR | stop DIR" >&2
    exit 2
}

# Absolute path of DIR (created by start; stop accepts one that is gone).
abs_dir() {
    local d=$1
    case $d in
        /*) ;;
        *) d=$PWD/$d ;;
    esac
    # Drop a trailing slash so the paths below look clean.
    [[ $d != / ]] && d=${d%/}
    printf '%s\n' "$d"
}

need_tools() {
    local missing=() c
    for c in munged slurmctld slurmd sbatch sinfo scontrol squeue scancel; do
        command -v "$c" >/dev/null 2>&1 || missing+=("$c")
    done
    if ((${#missing[@]})); then
        die "missing command(s): ${missing[*]}; on Debian: apt-get install slurmctld slurmd slurm-client munge"
    fi
}

need_root() {
    [[ $(id -u) -eq 0 ]] || die "must run as root (slurmd needs root to start job steps); try: sudo $0 $*"
}

# True if something listens on TCP port $1 (ss if present, else try to connect).
port_busy() {
    local p=$1
    if command -v ss >/dev/null 2>&1; then
        [[ -n $(ss -Htln "sport = :$p" 2>/dev/null) ]]
    else
        (exec 3<>"/dev/tcp/127.0.0.1/$p") 2>/dev/null
    fi
}

# Two free consecutive ports, trying 16817/16818 first.
pick_ports() {
    local p
    for ((p = 16817; p < 17817; p += 2)); do
        if ! port_busy "$p" && ! port_busy "$((p + 1))"; then
            echo "$p $((p + 1))"
            return 0
        fi
    done
    return 1
}

# Pid from pid file $1 if that process is alive and its command line names
# $2 (DIR), so a stale pid file can never make us signal a stranger.
live_pid() {
    local file=$1 dir=$2 pid cmd
    # Daemons delete their pid file on exit, so it may vanish at any time.
    pid=$({ tr -dc '0-9' <"$file"; } 2>/dev/null) || return 1
    [[ -n $pid ]] || return 1
    cmd=$({ tr '\0' ' ' <"/proc/$pid/cmdline"; } 2>/dev/null) || return 1
    [[ $cmd == *"$dir/"* ]] || return 1
    echo "$pid"
}

# Stop the daemon of pid file $1 for DIR $2: TERM, wait up to 10 s, then KILL.
stop_daemon() {
    local file=$1 dir=$2 name=$3 pid i
    if pid=$(live_pid "$file" "$dir"); then
        kill -TERM "$pid" 2>/dev/null || true
        # live_pid, not kill -0: an exited daemon may linger as a zombie
        # (empty cmdline) until init reaps it.
        for ((i = 0; i < 100; i++)); do
            live_pid "$file" "$dir" >/dev/null || break
            sleep 0.1
        done
        if live_pid "$file" "$dir" >/dev/null; then
            echo "$prog: $name (pid $pid) ignored SIGTERM; sending SIGKILL" >&2
            kill -KILL "$pid" 2>/dev/null || true
        fi
    fi
    rm -f "$file"
}

# slurmstepd processes of this cluster: slurmd hands them its environment,
# which holds SLURM_CONF=DIR/slurm.conf (set by start below).
stepd_pids() {
    local conf=$1 p
    for p in $(pgrep -x slurmstepd 2>/dev/null || true); do
        # The process may end meanwhile: hide the failed redirection too.
        if { tr '\0' '\n' <"/proc/$p/environ"; } 2>/dev/null | grep -qxF "SLURM_CONF=$conf"; then
            echo "$p"
        fi
    done
}

show_logs() {
    local dir=$1 f
    for f in "$dir"/log/munged.log "$dir"/log/slurmctld.log "$dir"/log/slurmd.log; do
        [[ -s $f ]] || continue
        echo "---- last lines of $f ----" >&2
        tail -n 20 "$f" >&2
    done
}

# Wait up to $2 tenths of a second for a live pid in pid file $1.
wait_pid() {
    local file=$1 tenths=$2 dir=$3 i
    for ((i = 0; i < tenths; i++)); do
        live_pid "$file" "$dir" >/dev/null && return 0
        sleep 0.1
    done
    return 1
}

cmd_start() {
    local dir node cpus ports ctld_port slurmd_port conf i state
    need_root start "$@"
    need_tools
    dir=$(abs_dir "$1")
    conf=$dir/slurm.conf

    # Refuse to start twice in the same folder.
    for i in munged slurmctld slurmd; do
        if live_pid "$dir/run/$i.pid" "$dir" >/dev/null; then
            die "$i already running for $dir; run: $prog stop $dir"
        fi
    done

    # sun_path holds 108 bytes, so the munge socket path must be shorter.
    ((${#dir} + 14 < 108)) || die "path too long for a unix socket: $dir/munge.socket"

    # munged wants its key, log, pid and seed in folders only root can write.
    mkdir -p "$dir"
    chmod 0755 "$dir"
    mkdir -p "$dir"/{munge,log,run,state,spool}
    chmod 0700 "$dir/munge"
    chmod 0755 "$dir"/{log,run,state,spool}
    rm -f "$dir/munge.socket" "$dir/munge.socket.lock"
    if [[ ! -s $dir/munge/munge.key ]]; then
        (umask 077 && dd if=/dev/urandom of="$dir/munge/munge.key" bs=1024 count=1 status=none)
    fi
    chmod 0400 "$dir/munge/munge.key"

    node=$(hostname -s)
    cpus=$(nproc)
    ports=$(pick_ports) || die "no two free TCP ports found in 16817-17817"
    read -r ctld_port slurmd_port <<<"$ports"

    # Empty plugstack, so /etc/slurm/plugstack.conf (next to the system
    # slurm.conf) is not read.
    : >"$dir/plugstack.conf"

    cat >"$conf" <<EOF
# Private one-node Slurm made by $prog; everything lives in $dir.
ClusterName=local
SlurmctldHost=$node(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$dir/munge.socket
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/run/slurmctld.pid
SlurmdPidFile=$dir/run/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
PlugStackConfig=$dir/plugstack.conf
# No cgroups: plain process tracking, no task binding.
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
MpiDefault=none
MailProg=/bin/true
# No accounting database: sacct will not work. Finished jobs stay in
# 'scontrol show job' for MinJobAge seconds and are logged to jobcomp.log.
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/filetxt
JobCompLoc=$dir/log/jobcomp.log
MinJobAge=300
SchedulerType=sched/backfill
ReturnToService=2
SlurmctldTimeout=30
SlurmdTimeout=60
InactiveLimit=0
KillWait=5
Waittime=0
NodeName=$node NodeHostname=$node NodeAddr=127.0.0.1 CPUs=$cpus State=UNKNOWN
PartitionName=debug Nodes=$node Default=YES MaxTime=INFINITE State=UP
EOF

    # Daemons and their slurmstepd children find the config via SLURM_CONF too.
    export SLURM_CONF=$conf

    # munged: own key, socket, pid, log and seed; --force because we are root.
    munged --force \
        --key-file="$dir/munge/munge.key" \
        --socket="$dir/munge.socket" \
        --pid-file="$dir/run/munged.pid" \
        --log-file="$dir/log/munged.log" \
        --seed-file="$dir/munge/munged.seed" ||
        { show_logs "$dir"; die "munged failed to start"; }
    wait_pid "$dir/run/munged.pid" 50 "$dir" ||
        { show_logs "$dir"; die "munged did not write $dir/run/munged.pid"; }

    # slurmctld: -c starts from an empty queue even if DIR was used before.
    slurmctld -c -f "$conf" ||
        { show_logs "$dir"; cmd_stop "$dir"; die "slurmctld failed to start"; }
    wait_pid "$dir/run/slurmctld.pid" 100 "$dir" ||
        { show_logs "$dir"; cmd_stop "$dir"; die "slurmctld did not start (no live pid in $dir/run/slurmctld.pid)"; }

    slurmd -f "$conf" -N "$node" ||
        { show_logs "$dir"; cmd_stop "$dir"; die "slurmd failed to start"; }
    wait_pid "$dir/run/slurmd.pid" 100 "$dir" ||
        { show_logs "$dir"; cmd_stop "$dir"; die "slurmd did not start (no live pid in $dir/run/slurmd.pid)"; }

    # Wait up to 30 s for the node to register and become idle.
    state=
    for ((i = 0; i < 150; i++)); do
        state=$(sinfo -h -n "$node" -o %T 2>/dev/null || true)
        [[ $state == idle ]] && break
        sleep 0.2
    done
    if [[ $state != idle ]]; then
        show_logs "$dir"
        cmd_stop "$dir"
        die "node $node not idle after 30 s (state: '${state:-no answer from slurmctld}')"
    fi

    echo "export SLURM_CONF=$conf"
}

cmd_stop() {
    local dir conf i left
    dir=$(abs_dir "$1")
    conf=$dir/slurm.conf
    [[ -d $dir ]] || return 0

    # Cancel this cluster's jobs while slurmctld is still up, so their
    # slurmstepd processes end cleanly.
    if [[ -r $conf ]] && live_pid "$dir/run/slurmctld.pid" "$dir" >/dev/null; then
        local jobs
        jobs=$(SLURM_CONF=$conf squeue -h -o %A 2>/dev/null || true)
        if [[ -n $jobs ]]; then
            # shellcheck disable=SC2086  # one word per job id
            SLURM_CONF=$conf scancel $jobs 2>/dev/null || true
            for ((i = 0; i < 50; i++)); do
                [[ -z $(stepd_pids "$conf") ]] && break
                sleep 0.2
            done
        fi
    fi

    stop_daemon "$dir/run/slurmd.pid" "$dir" slurmd
    stop_daemon "$dir/run/slurmctld.pid" "$dir" slurmctld
    stop_daemon "$dir/run/munged.pid" "$dir" munged

    # Any slurmstepd of this cluster still alive (its job ignored scancel).
    left=$(stepd_pids "$conf")
    if [[ -n $left ]]; then
        echo "$prog: killing leftover slurmstepd of $dir: ${left//$'\n'/ }" >&2
        # shellcheck disable=SC2086  # one word per pid
        kill -KILL $left 2>/dev/null || true
    fi
    rm -f "$dir/munge.socket" "$dir/munge.socket.lock"
}

(($# == 2)) || usage
case $1 in
    start) cmd_start "$2" ;;
    stop) cmd_stop "$2" ;;
    *) usage ;;
esac
