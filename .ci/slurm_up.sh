#!/usr/bin/env bash
# Bring up a one-node SLURM cluster on localhost for the SLURM smoke test
# (tests/test_workflow_slurm.py). Needs root and Debian's slurm-wlm + munge:
#
#   .ci/slurm_up.sh             # fails with a message if something is missing
#   .ci/slurm_up.sh --install   # apt-get installs slurmctld/slurmd/slurm-client/munge first
#   .ci/slurm_down.sh           # stops exactly the daemons this script started
#
# Everything lives in a state folder ($LAPJOINT_SLURM_STATE, default
# /tmp/lapjoint-slurm): munge key and socket, spool and state directories, logs, and
# the PIDs of munged, slurmctld and slurmd. The one file outside it is
# /etc/slurm/slurm.conf: srun inside a job step runs with SLURM_CONF removed from its
# environment (snakemake-executor-plugin-slurm-jobstep drops every SLURM_* variable),
# so the configuration must sit at the compiled-in default path. A slurm.conf that was
# there before is moved into the state folder and put back by slurm_down.sh.
#
# The daemons listen on 127.0.0.1 only (CommunicationParameters=NoCtldInAddrAny,
# NoInAddrAny, with every address set to 127.0.0.1). Idempotent: if the cluster is
# already up and answering, it says so and exits 0.
#
# Exit status: 0 up; 2 this machine cannot run it (not root, packages missing or not
# installable), so a caller may skip; 1 the bring-up failed (the daemons' logs are
# printed and whatever was started is stopped again).
set -euo pipefail

STATE=${LAPJOINT_SLURM_STATE:-/tmp/lapjoint-slurm}
CONF=/etc/slurm/slurm.conf
MARKER="# lapjoint smoke-test cluster (written by .ci/slurm_up.sh)"
TIMEOUT=${LAPJOINT_SLURM_UP_TIMEOUT:-60}

die() { # a failure of the bring-up itself
    echo "slurm_up: $*" >&2
    exit 1
}

unavailable() { # this machine cannot run it (not root, packages missing): exit 2
    echo "slurm_up: $*" >&2
    exit 2
}

fail_started() { # after daemons were started: show their logs, stop them, fail
    local log
    echo "slurm_up: $*" >&2
    for log in "$STATE"/log/*; do
        [[ -s $log ]] || continue
        echo "---- last lines of $log" >&2
        tail -n 15 "$log" >&2
    done
    "$(dirname "$0")/slurm_down.sh" >&2 || true
    exit 1
}

install=0
for arg in "$@"; do
    case $arg in
        --install) install=1 ;;
        -h | --help)
            sed -n '2,/^set -euo/p' "$0" | sed '$d'
            exit 0
            ;;
        *) die "unknown argument '$arg' (use --install or nothing)" ;;
    esac
done

[[ $(id -u) -eq 0 ]] || unavailable "must run as root (it starts munged, slurmctld and slurmd and writes $CONF)"
case $STATE in
    /*) ;;
    *) die "LAPJOINT_SLURM_STATE must be an absolute path, got '$STATE'" ;;
esac

needed=(munged mungekey slurmctld slurmd sinfo squeue sbatch srun scontrol)
missing() {
    local cmd
    for cmd in "${needed[@]}"; do
        command -v "$cmd" >/dev/null 2>&1 || echo "$cmd"
    done
}
if [[ -n $(missing) && $install -eq 1 ]]; then
    echo "slurm_up: installing Debian packages slurmctld slurmd slurm-client munge"
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq || unavailable "apt-get update failed"
    apt-get install -y -qq --no-install-recommends slurmctld slurmd slurm-client munge >/dev/null ||
        unavailable "apt-get install slurmctld slurmd slurm-client munge failed"
fi
if [[ -n $(missing) ]]; then
    unavailable "missing commands: $(missing | tr '\n' ' ')- install Debian's slurm-wlm and munge" \
        "(apt-get install -y slurm-wlm munge) or run '$0 --install'"
fi

pid_alive() { # pid_alive NAME: the PID recorded for NAME runs a process of that name
    local file=$STATE/$1.pid pid
    [[ -s $file ]] || return 1
    pid=$(<"$file")
    [[ -r /proc/$pid/comm ]] && [[ $(</proc/"$pid"/comm) == "$1" ]]
}

node_state() {
    sinfo --noheader --nodes=localhost --format=%T 2>/dev/null | head -n1 | tr -d '*~#!%$@^-' || true
}

if pid_alive munged && pid_alive slurmctld && pid_alive slurmd && grep -qxF "$MARKER" "$CONF" 2>/dev/null; then
    state=$(node_state)
    if [[ $state == idle || $state == mixed || $state == allocated ]]; then
        echo "slurm_up: already up (node localhost $state, state in $STATE)"
        exit 0
    fi
fi

# Anything half-started by an earlier call goes first (only our own PIDs).
if [[ -d $STATE ]]; then
    "$(dirname "$0")/slurm_down.sh"
fi

mkdir -p "$STATE"/{munge,ctld,spool,log}
chmod 700 "$STATE"/munge
mungekey --create --keyfile="$STATE/munge/munge.key" --bits=1024 --force >/dev/null 2>&1 ||
    { dd if=/dev/urandom of="$STATE/munge/munge.key" bs=128 count=1 status=none; }
chmod 400 "$STATE/munge/munge.key"

memory_mb=$(slurmd -C 2>/dev/null | sed -n 's/.*RealMemory=\([0-9]*\).*/\1/p')
if [[ -z $memory_mb ]]; then
    memory_mb=$(awk '/^MemTotal:/ {print int($2 / 1024)}' /proc/meminfo)
fi
cpus=$(nproc)

if [[ -e $CONF ]] && ! grep -qxF "$MARKER" "$CONF"; then
    cp -p "$CONF" "$STATE/slurm.conf.before"
    echo "slurm_up: kept the existing $CONF as $STATE/slurm.conf.before (slurm_down.sh restores it)"
fi
mkdir -p "$(dirname "$CONF")"
cat >"$CONF" <<EOF
$MARKER
# State, logs and PIDs: $STATE. Remove with .ci/slurm_down.sh.
ClusterName=lapjoint
SlurmctldHost=localhost(127.0.0.1)
CommunicationParameters=NoCtldInAddrAny,NoInAddrAny
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$STATE/munge/munge.socket
StateSaveLocation=$STATE/ctld
SlurmdSpoolDir=$STATE/spool
SlurmctldPidFile=$STATE/ctld/slurmctld.pidfile
SlurmdPidFile=$STATE/spool/slurmd.pidfile
SlurmctldLogFile=$STATE/log/slurmctld.log
SlurmdLogFile=$STATE/log/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
# No cgroups in this sandbox: track processes by /proc, no task binding.
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
# No slurmdbd: sacct has nothing to read, so job states come from squeue, which
# shows a finished job for MinJobAge seconds. snakemake-executor-plugin-slurm
# polls at most every 180 s, so keep finished jobs well past that.
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MinJobAge=300
MpiDefault=none
SwitchType=switch/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
ReturnToService=2
KillWait=5
InactiveLimit=0
Waittime=0
NodeName=localhost NodeAddr=127.0.0.1 NodeHostname=localhost CPUs=$cpus RealMemory=$memory_mb State=UNKNOWN
PartitionName=main Nodes=localhost Default=YES MaxTime=INFINITE State=UP
EOF
chmod 644 "$CONF"

start() { # start NAME COMMAND...: run in the background, record the PID
    local name=$1
    shift
    nohup "$@" </dev/null >>"$STATE/log/$name.out" 2>&1 &
    echo $! >"$STATE/$name.pid"
}

start munged munged --foreground --force \
    --socket="$STATE/munge/munge.socket" --key-file="$STATE/munge/munge.key" \
    --pid-file="$STATE/munge/munged.pid" --seed-file="$STATE/munge/munged.seed" \
    --log-file="$STATE/log/munged.log"
for _ in $(seq 50); do
    [[ -S $STATE/munge/munge.socket ]] && break
    sleep 0.1
done
[[ -S $STATE/munge/munge.socket ]] || fail_started "munged did not start"

start slurmctld slurmctld -D -i
start slurmd slurmd -D -N localhost

deadline=$((SECONDS + TIMEOUT))
while :; do
    state=$(node_state)
    [[ $state == idle ]] && break
    for name in munged slurmctld slurmd; do
        pid_alive "$name" || fail_started "$name exited"
    done
    if ((SECONDS >= deadline)); then
        fail_started "node localhost not idle after ${TIMEOUT}s (state '${state:-no answer}')"
    fi
    sleep 0.5
done
echo "slurm_up: one-node SLURM up on localhost ($cpus CPUs, ${memory_mb} MB, partition main);" \
    "PIDs munged $(<"$STATE/munged.pid") slurmctld $(<"$STATE/slurmctld.pid") slurmd $(<"$STATE/slurmd.pid")"
