#!/usr/bin/env bash
# Stop the one-node SLURM cluster that .ci/slurm_up.sh started: cancel its jobs, end
# exactly the munged, slurmctld and slurmd whose PIDs it recorded (a PID is signalled
# only while it still runs a process of that name), put back the /etc/slurm/slurm.conf
# that was there before (or remove ours), and delete the state folder.
# Idempotent: with nothing running it only tidies up and exits 0.
set -uo pipefail

STATE=${LAPJOINT_SLURM_STATE:-/tmp/lapjoint-slurm}
CONF=/etc/slurm/slurm.conf
MARKER="# lapjoint smoke-test cluster (written by .ci/slurm_up.sh)"

case $STATE in
    /*) ;;
    *)
        echo "slurm_down: LAPJOINT_SLURM_STATE must be an absolute path, got '$STATE'" >&2
        exit 1
        ;;
esac

if [[ ! -d $STATE ]]; then
    echo "slurm_down: nothing to stop ($STATE does not exist)"
    exit 0
fi

recorded_pid() { # recorded_pid NAME: the PID in NAME.pid if it still runs NAME
    local file=$STATE/$1.pid pid
    [[ -s $file ]] || return 1
    pid=$(<"$file")
    [[ $pid =~ ^[0-9]+$ ]] || return 1
    [[ -r /proc/$pid/comm && $(</proc/"$pid"/comm) == "$1" ]] || return 1
    echo "$pid"
}

# Jobs first, while slurmctld and slurmd can still end their job steps.
if recorded_pid slurmctld >/dev/null && grep -qxF "$MARKER" "$CONF" 2>/dev/null; then
    if [[ -n $(squeue --noheader --format=%i 2>/dev/null) ]]; then
        scancel --full --quiet $(squeue --noheader --format=%i 2>/dev/null) 2>/dev/null || true
        for _ in $(seq 20); do
            [[ -z $(squeue --noheader --states=PENDING,RUNNING,COMPLETING --format=%i 2>/dev/null) ]] && break
            sleep 0.5
        done
    fi
fi

for name in slurmd slurmctld munged; do
    pid=$(recorded_pid "$name") || continue
    kill -TERM "$pid" 2>/dev/null || continue
    for _ in $(seq 50); do
        [[ -d /proc/$pid ]] || break
        sleep 0.1
    done
    if [[ -d /proc/$pid ]]; then
        echo "slurm_down: $name ($pid) ignored SIGTERM, sending SIGKILL" >&2
        kill -KILL "$pid" 2>/dev/null || true
    fi
    echo "slurm_down: stopped $name ($pid)"
done

if [[ -e $STATE/slurm.conf.before ]]; then
    cp -p "$STATE/slurm.conf.before" "$CONF"
    echo "slurm_down: restored the earlier $CONF"
elif grep -qxF "$MARKER" "$CONF" 2>/dev/null; then
    rm -f "$CONF"
fi
rm -rf "$STATE"
echo "slurm_down: removed $STATE"
