#!/usr/bin/env bash
# cluster.sh — a private one-node Slurm cluster on this machine, for testing the
# raycost job-array scripts. Debian 12 packages, no systemd needed.
#
#   bash scripts/slurm/cluster.sh up      # install if missing, start munged/slurmctld/slurmd, wait for idle
#   bash scripts/slurm/cluster.sh down    # stop exactly the daemons `up` started (by recorded pid)
#   bash scripts/slurm/cluster.sh status  # pids and sinfo
#   eval "$(bash scripts/slurm/cluster.sh env)"   # point sbatch/squeue/... at this cluster
#
# Everything lives in $RAYCOST_SLURM_DIR (default /tmp/raycost-slurm): slurm.conf, munge key and
# socket, state, spool, logs, pids. Clients find the cluster through SLURM_CONF=$DIR/slurm.conf.
# The daemons listen on their own ports and munge socket, so a system Slurm/munge is left alone.
#
# Environment:
#   RAYCOST_SLURM_DIR        state dir                      (/tmp/raycost-slurm)
#   RAYCOST_SLURM_CTLD_PORT  slurmctld port                 (16817)
#   RAYCOST_SLURM_SLURMD_PORT slurmd port                   (16818)
#   RAYCOST_SLURM_TIMEOUT    seconds to wait for the node to be idle, and for daemons to exit (60)
#
# Exit codes: 0 ok; 3 Slurm cannot be made available here (not root and not installed, or apt-get
# failed) — the line starting "cluster.sh: unavailable:" gives the reason, and a caller may turn
# it into a skip; 1 anything else (the daemons' log tails are printed).
set -euo pipefail

DIR=${RAYCOST_SLURM_DIR:-/tmp/raycost-slurm}
CTLD_PORT=${RAYCOST_SLURM_CTLD_PORT:-16817}
SLURMD_PORT=${RAYCOST_SLURM_SLURMD_PORT:-16818}
TIMEOUT=${RAYCOST_SLURM_TIMEOUT:-60}
PKGS=(slurmctld slurmd slurm-client munge)
# Commands the packages above provide, which this script and submit.sh use.
CMDS=(slurmctld slurmd munged mungekey sbatch squeue sinfo scontrol scancel sacct)
# Order matters for `down`: slurmd first, munged last (Slurm needs it to shut down cleanly).
DAEMONS=(slurmd slurmctld munged)

export PATH="$PATH:/usr/sbin:/sbin"
export SLURM_CONF="$DIR/slurm.conf"

log() { printf 'cluster.sh: %s\n' "$*" >&2; }
die() { log "error: $*"; exit 1; }
unavailable() { log "unavailable: $*"; exit 3; }

missing_cmds() {
    local c out=()
    for c in "${CMDS[@]}"; do command -v "$c" >/dev/null 2>&1 || out+=("$c"); done
    echo "${out[*]}"
}

# --- install -------------------------------------------------------------------------------
install_packages() {
    local missing
    missing=$(missing_cmds)
    [[ -z $missing ]] && return 0
    [[ $(id -u) -eq 0 ]] || unavailable "missing commands ($missing) and not root, so cannot apt-get install ${PKGS[*]}"
    command -v apt-get >/dev/null 2>&1 || unavailable "missing commands ($missing) and no apt-get on this machine"
    log "installing ${PKGS[*]} with apt-get (missing: $missing)"
    local aptlog="$DIR/log/apt.log" made_policy=0 rc=0
    # Debian's maintainer scripts would start munge/slurm through invoke-rc.d; forbid that for the
    # duration (policy-rc.d exit 101 = "action forbidden"), unless a policy is already in place.
    if [[ ! -e /usr/sbin/policy-rc.d ]]; then
        printf '#!/bin/sh\n# temporary, from raycost scripts/slurm/cluster.sh\nexit 101\n' >/usr/sbin/policy-rc.d
        chmod 755 /usr/sbin/policy-rc.d
        made_policy=1
        trap 'rm -f /usr/sbin/policy-rc.d' EXIT # also if interrupted
    fi
    {
        export DEBIAN_FRONTEND=noninteractive
        apt-get -o DPkg::Lock::Timeout=300 update -q &&
            apt-get -o DPkg::Lock::Timeout=300 -o Dpkg::Options::=--force-confdef \
                -o Dpkg::Options::=--force-confold install -y -q --no-install-recommends "${PKGS[@]}"
    } >"$aptlog" 2>&1 </dev/null || rc=$?
    if [[ $made_policy -eq 1 ]]; then rm -f /usr/sbin/policy-rc.d; trap - EXIT; fi
    if [[ $rc -ne 0 ]]; then
        tail -n 15 "$aptlog" | sed 's/^/  apt: /' >&2
        unavailable "apt-get could not install ${PKGS[*]} (exit $rc; full log $aptlog)"
    fi
    missing=$(missing_cmds)
    [[ -z $missing ]] || unavailable "installed ${PKGS[*]} but still missing: $missing"
}

# --- pid bookkeeping -------------------------------------------------------------------------
# True if pid runs program NAME (any, if empty) and has not exited (an exited daemon is a zombie until pid 1,
# which may be slow to do so, reaps it).
is_live() { # pid name
    local stat
    stat=$(cat 2>/dev/null "/proc/$1/stat") || return 1
    [[ ${stat##*) } != Z* ]] || return 1
    [[ -z $2 || $(cat 2>/dev/null "/proc/$1/comm") == "$2" ]]
}

# $DIR/pids/NAME.pid holds the pid we started; a pid only counts if it is still that program.
pid_of() {
    local name=$1 f="$DIR/pids/$1.pid" pid
    [[ -s $f ]] || return 1
    pid=$(<"$f")
    [[ $pid =~ ^[0-9]+$ ]] || return 1
    is_live "$pid" "$name" || return 1
    printf '%s\n' "$pid"
}

# The pid a daemon wrote to its own pid file (they fork into the background).
wait_pidfile() {
    local name=$1 pidfile=$2 i pid
    for ((i = 0; i < 10 * 20; i++)); do
        if [[ -s $pidfile ]]; then
            pid=$(<"$pidfile")
            if [[ $pid =~ ^[0-9]+$ ]] && is_live "$pid" "$name"; then
                printf '%s\n' "$pid" >"$DIR/pids/$name.pid"
                return 0
            fi
        fi
        sleep 0.1
    done
    return 1
}

# "pid comm" of every live process of *this* cluster: the daemons, the slurmstepd that slurmd
# daemonises for each job step, the job processes under them, and orphans of any of these. They
# carry SLURM_CONF=$SLURM_CONF in their environment (job processes also SLURM_JOB_ID); job
# processes that dropped it are found as descendants of one of our slurmstepd. This shell and
# its ancestors are never listed.
cluster_processes() {
    local p pid ppid comm stat rest envs q
    local -A parent=() name=() ours=() mine=()
    local -a envv
    pid=$$
    while [[ $pid =~ ^[0-9]+$ && $pid -gt 1 ]]; do
        mine[$pid]=1
        stat=$(cat 2>/dev/null "/proc/$pid/stat") || break
        rest=${stat##*) }
        read -r _ pid _ <<<"$rest"
    done
    for p in /proc/[0-9]*; do
        pid=${p#/proc/}
        [[ -n ${mine[$pid]:-} ]] && continue
        stat=$(cat 2>/dev/null "$p/stat") || continue
        rest=${stat##*) }
        [[ $rest == Z* ]] && continue # exited, waiting to be reaped
        read -r _ ppid _ <<<"$rest"
        comm=${stat#*(}
        comm=${comm%)*}
        parent[$pid]=$ppid
        name[$pid]=$comm
        mapfile -d '' -t envv 2>/dev/null <"$p/environ" || continue
        envs=$'\n'$(printf '%s\n' "${envv[@]}")$'\n'
        [[ $envs == *$'\n'"SLURM_CONF=$SLURM_CONF"$'\n'* ]] || continue
        case $comm in
        slurmctld | slurmscriptd | slurmd | slurmstepd | munged) ours[$pid]=1 ;;
        *) [[ $envs == *$'\n'SLURM_JOB_ID=* ]] && ours[$pid]=1 ;;
        esac
    done
    for pid in "${!name[@]}"; do
        q=${parent[$pid]:-1}
        while [[ -z ${ours[$pid]:-} && -n ${name[$q]:-} && $q -gt 1 ]]; do
            [[ -n ${ours[$q]:-} && ${name[$q]} == slurmstepd ]] && ours[$pid]=1
            q=${parent[$q]:-1}
        done
    done
    for pid in "${!ours[@]}"; do printf '%s %s\n' "$pid" "${name[$pid]}"; done
}

# Stop pids: SIGTERM, up to SECONDS to exit, then SIGKILL.
stop_pids() { # seconds pid...
    local secs=$1 pid i left
    shift
    [[ $# -gt 0 ]] || return 0
    kill -TERM "$@" 2>/dev/null || true
    for ((i = 0; i <= secs * 10; i++)); do
        left=()
        for pid in "$@"; do is_live "$pid" "" && left+=("$pid"); done
        [[ ${#left[@]} -eq 0 ]] && return 0
        sleep 0.1
    done
    log "still running after SIGTERM and ${secs}s, sending SIGKILL: ${left[*]}"
    kill -KILL "${left[@]}" 2>/dev/null || true
    for ((i = 0; i < 50; i++)); do
        left=()
        for pid in "$@"; do is_live "$pid" "" && left+=("$pid"); done
        [[ ${#left[@]} -eq 0 ]] && return 0
        sleep 0.1
    done
    log "warning: still present after SIGKILL: ${left[*]}"
}

log_tails() {
    local f
    for f in "$DIR"/log/munged.log "$DIR"/log/slurmctld.log "$DIR"/log/slurmd.log; do
        [[ -s $f ]] || continue
        printf -- '--- last lines of %s ---\n' "$f" >&2
        tail -n 20 "$f" >&2
    done
}

# --- config ---------------------------------------------------------------------------------
write_conf() {
    local node=$1 cpus mem
    cpus=$(nproc)
    # slurmd drains a node whose configured memory exceeds what it measures; leave 5% headroom.
    # (/proc/meminfo, i.e. what `free` shows: minimal images lack procps.)
    mem=$(awk '/^MemTotal:/ { printf "%d", $2 / 1024 * 0.95 }' /proc/meminfo)
    [[ $mem -gt 0 ]] || mem=1
    : >"$DIR/plugstack.conf" # don't pick up /etc/slurm/plugstack.conf
    cat >"$DIR/slurm.conf.tmp" <<EOF
# Generated by raycost scripts/slurm/cluster.sh — a private one-node test cluster.
ClusterName=raycost
MailProg=/bin/true
SlurmctldHost=$node(127.0.0.1)
SlurmctldPort=$CTLD_PORT
SlurmdPort=$SLURMD_PORT
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$DIR/munge/munge.socket
PlugStackConfig=$DIR/plugstack.conf
StateSaveLocation=$DIR/state
SlurmdSpoolDir=$DIR/spool/slurmd-%n
SlurmctldPidFile=$DIR/run/slurmctld.pid
SlurmdPidFile=$DIR/run/slurmd.pid
SlurmctldLogFile=$DIR/log/slurmctld.log
SlurmdLogFile=$DIR/log/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
# No cgroups: processes are tracked through /proc, tasks are not bound.
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SwitchType=switch/none
MpiDefault=none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/backfill
# Let a dependent job fail instead of pending forever when a dependency fails.
SchedulerParameters=kill_invalid_depend
JobAcctGatherType=jobacct_gather/none
# No slurmdbd: sacct only works as "sacct -c" on the job-completion text file below.
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/filetxt
JobCompLoc=$DIR/log/jobcomp.txt
ReturnToService=2
SlurmctldTimeout=60
SlurmdTimeout=120
InactiveLimit=0
# Keep finished jobs visible to "scontrol show job" for 10 minutes.
MinJobAge=600
KillWait=10
Waittime=0
NodeName=$node NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$mem State=UNKNOWN
PartitionName=debug Nodes=$node Default=YES MaxTime=INFINITE State=UP
EOF
    mv "$DIR/slurm.conf.tmp" "$SLURM_CONF"
}

node_name() {
    local n
    n=$(hostname -s 2>/dev/null || true)
    [[ -n $n ]] || n=$(uname -n)
    printf '%s\n' "${n%%.*}"
}

# --- up / down -------------------------------------------------------------------------------
cmd_up() {
    local t0 node state i d
    t0=$(date +%s%N)
    mkdir -p "$DIR/log" "$DIR/pids"
    # The munge key lives here: refuse a directory someone else made (e.g. in a shared /tmp).
    [[ -O $DIR ]] || die "$DIR belongs to another user; set RAYCOST_SLURM_DIR"
    if pid_of slurmctld >/dev/null && pid_of slurmd >/dev/null && pid_of munged >/dev/null &&
        [[ $(sinfo -h -o %T 2>/dev/null) =~ ^(idle|mixed|allocated) ]]; then
        log "already up (SLURM_CONF=$SLURM_CONF)"
        return 0
    fi
    # Anything half-started from an earlier attempt goes first, so `up` always starts clean.
    if [[ -n $(ls -A "$DIR/pids") || -n $(cluster_processes) ]]; then
        log "stopping leftovers of an earlier run"
        cmd_down
    fi
    install_packages
    [[ $(id -u) -eq 0 ]] || unavailable "the test cluster runs its daemons as root (SlurmUser=root); run as root"

    # munged requires every directory above its socket to be searchable by all users (jobs of any
    # user talk to it), and the key to be private: socket in munge/ (0755), key in munge-key/ (0700).
    chmod 755 "$DIR"
    mkdir -p "$DIR/munge" "$DIR/munge-key"
    chmod 755 "$DIR/munge"
    chmod 700 "$DIR/munge-key"
    rm -rf "$DIR/state" "$DIR/spool" "$DIR/run"
    mkdir -p "$DIR/state" "$DIR/spool" "$DIR/run"
    : >"$DIR/log/munged.log"
    : >"$DIR/log/slurmctld.log"
    : >"$DIR/log/slurmd.log"
    : >"$DIR/log/jobcomp.txt" # job ids restart at 1 with the fresh state; so does this log
    node=$(node_name)
    mkdir -p "$DIR/spool/slurmd-$node"
    write_conf "$node"

    # munge: our own key and socket; munged insists on key mode 0600 owned by its user.
    if [[ ! -s $DIR/munge-key/munge.key ]]; then
        mungekey --create --keyfile="$DIR/munge-key/munge.key" 2>/dev/null ||
            dd if=/dev/urandom of="$DIR/munge-key/munge.key" bs=1 count=1024 status=none
    fi
    chmod 600 "$DIR/munge-key/munge.key"
    rm -f "$DIR/munge/munge.socket" "$DIR/munge/munge.socket.lock" "$DIR/munge/munged.pid"
    munged --socket="$DIR/munge/munge.socket" --key-file="$DIR/munge-key/munge.key" \
        --pid-file="$DIR/munge/munged.pid" --seed-file="$DIR/munge/munged.seed" \
        --log-file="$DIR/log/munged.log" </dev/null >>"$DIR/log/munged.log" 2>&1 ||
        { log_tails; cmd_down; die "munged failed to start"; }
    wait_pidfile munged "$DIR/munge/munged.pid" || { log_tails; cmd_down; die "munged wrote no pid file"; }

    # -c: discard any saved job state; -i: ignore errors reading state (there is none).
    slurmctld -c -i -f "$SLURM_CONF" </dev/null >>"$DIR/log/slurmctld.log" 2>&1 ||
        { log_tails; cmd_down; die "slurmctld failed to start"; }
    wait_pidfile slurmctld "$DIR/run/slurmctld.pid" || { log_tails; cmd_down; die "slurmctld wrote no pid file"; }
    slurmd -N "$node" -f "$SLURM_CONF" </dev/null >>"$DIR/log/slurmd.log" 2>&1 ||
        { log_tails; cmd_down; die "slurmd failed to start"; }
    wait_pidfile slurmd "$DIR/run/slurmd.pid" || { log_tails; cmd_down; die "slurmd wrote no pid file"; }

    state=
    for ((i = 0; i < TIMEOUT * 2; i++)); do
        state=$(sinfo -h -n "$node" -o %T 2>/dev/null || true)
        [[ $state == idle ]] && break
        for d in "${DAEMONS[@]}"; do
            pid_of "$d" >/dev/null || { log_tails; cmd_down; die "$d exited during start-up"; }
        done
        sleep 0.5
    done
    if [[ $state != idle ]]; then
        log_tails
        scontrol show node "$node" >&2 2>/dev/null || true
        cmd_down
        die "node $node not idle after ${TIMEOUT}s (state: ${state:-none})"
    fi
    log "up in $(( ($(date +%s%N) - t0) / 1000000 )) ms: node $node ($(nproc) CPUs), partition debug;" \
        "pids munged=$(pid_of munged) slurmctld=$(pid_of slurmctld) slurmd=$(pid_of slurmd)"
    log "use it with: export SLURM_CONF=$SLURM_CONF"
}

cmd_down() {
    local name pid p comm jobs i
    local -a job_pids stepd_pids stray
    mkdir -p "$DIR/pids"
    # Cancel jobs first: slurmctld has slurmd end them cleanly (epilogue, job state).
    if pid_of slurmctld >/dev/null && pid_of munged >/dev/null; then
        jobs=$(squeue -h -o %A 2>/dev/null || true)
        if [[ -n $jobs ]]; then
            log "cancelling jobs: $(echo "$jobs" | tr '\n' ' ')"
            # shellcheck disable=SC2086 # one job id per word
            scancel $jobs 2>/dev/null || true
            for ((i = 0; i < 20 * 2; i++)); do
                [[ -z $(squeue -h -o %A 2>/dev/null) ]] && break
                sleep 0.5
            done
        fi
    fi
    # Whatever job processes are left (slurmctld was gone, or a job ignored the cancel) are
    # stopped by pid, then the daemons we started, slurmstepd, and munged last (the others need
    # it to shut down cleanly).
    job_pids=() stepd_pids=()
    while read -r p comm; do
        case $comm in
        slurmctld | slurmscriptd | slurmd | munged) ;;
        slurmstepd) stepd_pids+=("$p") ;;
        *) job_pids+=("$p") ;;
        esac
    done < <(cluster_processes)
    if [[ ${#job_pids[@]} -gt 0 ]]; then
        log "stopping job processes: ${job_pids[*]}"
        stop_pids 10 "${job_pids[@]}"
    fi
    for name in "${DAEMONS[@]}"; do
        if [[ $name == munged && ${#stepd_pids[@]} -gt 0 ]]; then
            log "stopping slurmstepd: ${stepd_pids[*]}"
            stop_pids 5 "${stepd_pids[@]}"
        fi
        if pid=$(pid_of "$name"); then
            log "stopping $name (pid $pid)"
            stop_pids "$TIMEOUT" "$pid"
        fi
        rm -f "$DIR/pids/$name.pid"
    done
    # Anything of this cluster still alive (say a daemon whose pid file was lost) goes by pid too.
    mapfile -t stray < <(cluster_processes)
    if [[ ${#stray[@]} -gt 0 ]]; then
        log "stopping leftovers: ${stray[*]}"
        stop_pids 5 "${stray[@]%% *}"
    fi
    mapfile -t stray < <(cluster_processes)
    [[ ${#stray[@]} -eq 0 ]] || die "processes of this cluster still running: ${stray[*]}"
    log "down"
}

cmd_status() {
    local name pid rc=0
    for name in "${DAEMONS[@]}"; do
        if pid=$(pid_of "$name"); then echo "$name: running (pid $pid)"; else echo "$name: not running"; rc=1; fi
    done
    [[ $rc -eq 0 ]] && sinfo
    return $rc
}

case ${1:-} in
up) cmd_up ;;
down) cmd_down ;;
status) cmd_status ;;
env) printf 'export SLURM_CONF=%q\n' "$SLURM_CONF" ;;
*)
    echo "usage: $0 up|down|status|env   (state dir: \$RAYCOST_SLURM_DIR, now $DIR)" >&2
    exit 2
    ;;
esac
