#!/usr/bin/env bash
# Throw-away single-node Slurm cluster on localhost, for tests that need a real
# scheduler (e.g. running a Snakemake workflow through Slurm).
#
# Everything (munge key/socket, slurm.conf, state, spool, logs, pid files) lives
# in <statedir>, so it never touches /etc/slurm, /etc/munge or a system munged.
# Needs root (SlurmUser=root, slurmd must run as root) and the Debian packages
# slurm-wlm and munge. Written for Debian bookworm (Slurm 22.05, munge 0.5.15).
set -euo pipefail

usage() {
    cat <<'EOF'
Usage: cluster.sh start <statedir>   start munged, slurmctld, slurmd; wait for the node
                                     to be idle; print "export SLURM_CONF=..." on stdout
       cluster.sh stop <statedir>    cancel jobs, stop the daemons started by "start"
                                     (idempotent; safe after a failed start)
       cluster.sh --help

Clients must be run with SLURM_CONF=<statedir>/slurm.conf in their environment.
Progress and errors go to stderr; only the export line goes to stdout, so
  eval "$(tests/slurm/cluster.sh start /tmp/slurm)"
works.
Environment: SLURM_START_TIMEOUT (seconds to wait for an idle node, default 60),
             SLURM_CTLD_PORT / SLURM_SLURMD_PORT (force ports instead of picking free ones).
EOF
}

log() { echo "cluster.sh: $*" >&2; }
die() { log "error: $*"; exit 1; }

# Marker put in the environment of every daemon we start. slurmstepd inherits it
# from slurmd, which lets "stop" find leftover step daemons belonging to this
# cluster (they are re-parented to init, so there is no pid file or parent link).
MARKER_VAR=LATENTPT_SLURM_STATEDIR

# Is a pid alive and running the expected program? Guards against pid reuse
# after a stale pid file.
pid_is() {
    local pid=$1 comm=$2
    [[ -n $pid && -r /proc/$pid/comm ]] || return 1
    [[ $(cat "/proc/$pid/comm" 2>/dev/null) == "$comm" ]] || return 1
    # A zombie has exited; its reaper (init here, not us) may be slow to collect it.
    local stat
    stat=$(cat "/proc/$pid/stat" 2>/dev/null) || return 1
    stat=${stat##*) }
    [[ ${stat%% *} != Z ]]
}

pid_from_file() { if [[ -s $1 ]]; then tr -dc '0-9' <"$1"; fi; }

# Is a TCP port free for listening?
port_free() {
    local p=$1
    if command -v ss >/dev/null; then
        [[ -z $(ss -Hltn "sport = :$p" 2>/dev/null) ]]
    else
        if (exec 3<>"/dev/tcp/127.0.0.1/$p") 2>/dev/null; then return 1; fi
    fi
}

# First free port in [start, start+500), skipping $2 (the other daemon's port).
pick_port() {
    local p=$1 avoid=${2:-}
    for ((; p < $1 + 500; p++)); do
        [[ $p == "$avoid" ]] && continue
        port_free "$p" && { echo "$p"; return; }
    done
    die "no free TCP port in $1..$(($1 + 499))"
}

show_logs() {
    local d=$1 f
    for f in "$d/munge/munged.log" "$d/log/slurmctld.log" "$d/log/slurmd.log"; do
        [[ -f $f ]] || continue
        log "---- last lines of $f ----"
        tail -n 25 "$f" >&2
    done
}

cmd_start() {
    local dir=$1 t_start
    t_start=$(date +%s%N)
    [[ $(id -u) == 0 ]] || die "must run as root (slurmd and SlurmUser=root need it)"
    local b
    for b in munged slurmctld slurmd sinfo; do
        command -v "$b" >/dev/null || die "$b not found; run: apt-get install -y slurm-wlm munge"
    done

    mkdir -p "$dir"
    dir=$(cd "$dir" && pwd -P)
    # Unix sockets (munge, slurmd spool <node>_<job>.<step>) are limited to 108 bytes.
    ((${#dir} <= 80)) || die "statedir path too long for unix sockets (${#dir} > 80 chars): $dir"

    local pidf
    for pidf in "$dir/munge/munged.pid:munged" "$dir/run/slurmctld.pid:slurmctld" "$dir/run/slurmd.pid:slurmd"; do
        if pid_is "$(pid_from_file "${pidf%%:*}")" "${pidf##*:}"; then
            die "a cluster is already running from $dir (${pidf##*:}); run: $0 stop $dir"
        fi
    done

    # 0755, not 0700: non-root clients must reach the munge socket, and munged
    # rejects group/other-writable directories on the key and socket paths.
    mkdir -p "$dir/munge" "$dir/state" "$dir/spool" "$dir/log" "$dir/run"
    chmod 0755 "$dir" "$dir/munge"
    chmod 0700 "$dir/state"

    # ---- munge -------------------------------------------------------------
    local mkey=$dir/munge/munge.key msock=$dir/munge/munge.socket
    if [[ ! -s $mkey ]]; then
        if command -v mungekey >/dev/null; then
            mungekey --create --keyfile="$mkey" >/dev/null
        else
            dd if=/dev/urandom of="$mkey" bs=1024 count=1 status=none
        fi
    fi
    # munged refuses keys readable by others or not owned by its user.
    chown root:root "$mkey"
    chmod 0600 "$mkey"
    rm -f "$msock" "$msock.lock"

    # Ensure a failed start does not leave daemons behind; logs stay for inspection.
    START_DIR=$dir
    trap 'rc=$?; if ((rc != 0)); then show_logs "$START_DIR"; cmd_stop "$START_DIR" || true; fi' EXIT

    env "$MARKER_VAR=$dir" munged \
        --socket="$msock" --key-file="$mkey" \
        --pid-file="$dir/munge/munged.pid" --log-file="$dir/munge/munged.log" \
        --seed-file="$dir/munge/munged.seed" \
        || die "munged failed to start"
    # Round-trip a credential to prove the daemon is usable before starting slurm.
    local i
    for ((i = 0; i < 50; i++)); do
        if munge -n -S "$msock" 2>/dev/null | unmunge -S "$msock" >/dev/null 2>&1; then break; fi
        sleep 0.1
    done
    ((i < 50)) || die "munged does not answer on $msock"

    # ---- slurm.conf ----------------------------------------------------------
    local host cpus mem_total mem ctld_port slurmd_port
    host=$(hostname -s)
    cpus=$(nproc)
    mem_total=$(free -m | awk '/^Mem:/ {print $2}')
    # slurmd drains a node whose configured RealMemory exceeds what it detects;
    # stay ~5% (at least 256 MiB) below the total.
    mem=$((mem_total - (mem_total / 20 > 256 ? mem_total / 20 : 256)))
    ((mem > 0)) || mem=$mem_total
    ctld_port=${SLURM_CTLD_PORT:-$(pick_port 16817)}
    slurmd_port=${SLURM_SLURMD_PORT:-$(pick_port 16818 "$ctld_port")}

    cat >"$dir/slurm.conf" <<EOF
# Generated by tests/slurm/cluster.sh; single-node throw-away test cluster.
ClusterName=latentpt-test
# Explicit address: works even where the short hostname does not resolve.
SlurmctldHost=$host(127.0.0.1)
SlurmUser=root
SlurmdUser=root
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$msock
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/run/slurmctld.pid
SlurmdPidFile=$dir/run/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
# No cgroups: tests may run in containers without a writable cgroup tree.
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerType=sched/backfill
# Start batch jobs at submit time rather than up to 3 s later (test latency).
SchedulerParameters=batch_sched_delay=0
# No slurmdbd: sacct will not work against this cluster.
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
MailProg=/bin/true
# A node that was down (e.g. from a previous run) comes back as soon as slurmd registers.
ReturnToService=2
# Keep finished jobs visible to scontrol/squeue for a while (status polling).
MinJobAge=600
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$mem State=UNKNOWN
PartitionName=debug Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF

    export SLURM_CONF=$dir/slurm.conf
    # -c: drop job/node state from a previous run in the same statedir.
    env "$MARKER_VAR=$dir" slurmctld -c -f "$SLURM_CONF" || die "slurmctld failed to start"
    env "$MARKER_VAR=$dir" slurmd -c -f "$SLURM_CONF" -N "$host" || die "slurmd failed to start"

    local timeout=${SLURM_START_TIMEOUT:-60} t0=$SECONDS state='' d pid
    while ((SECONDS - t0 < timeout)); do
        state=$(sinfo -h -n "$host" -o %t 2>/dev/null || true)
        [[ $state == idle ]] && break
        # Fail fast if a daemon died (e.g. bad config) instead of waiting out the
        # timeout; the pid files appear shortly after the daemons fork.
        for d in slurmctld slurmd; do
            pid=$(pid_from_file "$dir/run/$d.pid")
            if [[ -n $pid ]] && ! pid_is "$pid" "$d"; then die "$d exited"; fi
            if [[ -z $pid ]] && ((SECONDS - t0 > 10)); then die "$d wrote no pid file"; fi
        done
        sleep 0.5
    done
    [[ $state == idle ]] || die "node $host not idle after ${timeout}s (sinfo state: '${state:-none}')"

    trap - EXIT
    log "cluster up in $((($(date +%s%N) - t_start) / 1000000)) ms: node $host, $cpus CPUs, ${mem} MiB, ports $ctld_port/$slurmd_port"
    echo "export SLURM_CONF=$dir/slurm.conf"
}

# Sends a signal, then waits up to `tenths` x 0.1 s for the process to go; fails if it stays.
signal_and_wait() {
    local pid=$1 comm=$2 sig=$3 tenths=$4 i
    kill "-$sig" "$pid" 2>/dev/null || true
    for ((i = 0; i < tenths; i++)); do
        pid_is "$pid" "$comm" || return 0
        sleep 0.1
    done
    return 1
}

# SIGTERM, wait up to ~15 s, then SIGKILL.
stop_pid() {
    local pid=$1 comm=$2
    pid_is "$pid" "$comm" || return 0
    signal_and_wait "$pid" "$comm" TERM 150 && return 0
    log "$comm ($pid) ignored SIGTERM; killing"
    signal_and_wait "$pid" "$comm" KILL 50 && return 0
    die "$comm ($pid) did not exit"
}

# Pids of processes carrying our marker with the given command name.
marked_pids() {
    local comm=$1 dir=$2 p
    for p in /proc/[0-9]*; do
        [[ $(cat "$p/comm" 2>/dev/null) == "$comm" ]] || continue
        { tr '\0' '\n' <"$p/environ"; } 2>/dev/null | grep -qxF "$MARKER_VAR=$dir" && echo "${p#/proc/}"
    done
    return 0
}

cmd_stop() {
    local dir=$1
    [[ -d $dir ]] || { log "nothing to stop: $dir does not exist"; return 0; }
    dir=$(cd "$dir" && pwd -P)
    local conf=$dir/slurm.conf pid i

    # Cancel jobs while the controller is still up, so their steps end cleanly.
    if [[ -f $conf ]] && pid_is "$(pid_from_file "$dir/run/slurmctld.pid")" slurmctld; then
        local jobs
        jobs=$(SLURM_CONF=$conf squeue -h -o %i 2>/dev/null || true)
        if [[ -n $jobs ]]; then
            # shellcheck disable=SC2086
            SLURM_CONF=$conf scancel $jobs 2>/dev/null || true
            for ((i = 0; i < 100; i++)); do
                [[ -z $(SLURM_CONF=$conf squeue -h -o %i 2>/dev/null || true) ]] && break
                sleep 0.1
            done
        fi
    fi

    stop_pid "$(pid_from_file "$dir/run/slurmd.pid")" slurmd
    # Also catch a slurmd that died before/without writing its pid file.
    for pid in $(marked_pids slurmd "$dir"); do stop_pid "$pid" slurmd; done
    for pid in $(marked_pids slurmstepd "$dir"); do stop_pid "$pid" slurmstepd; done
    stop_pid "$(pid_from_file "$dir/run/slurmctld.pid")" slurmctld
    for pid in $(marked_pids slurmctld "$dir"); do stop_pid "$pid" slurmctld; done
    stop_pid "$(pid_from_file "$dir/munge/munged.pid")" munged
    for pid in $(marked_pids munged "$dir"); do stop_pid "$pid" munged; done

    rm -f "$dir/run/slurmctld.pid" "$dir/run/slurmd.pid" "$dir/munge/munged.pid"
    log "cluster in $dir stopped"
}

case ${1:-} in
-h | --help | help) usage ;;
start | stop)
    [[ $# == 2 ]] || { usage >&2; exit 2; }
    "cmd_$1" "$2"
    ;;
*) usage >&2; exit 2 ;;
esac
