#!/usr/bin/env bash
# A single-node Slurm on this machine, for testing `tread sweep --backend slurm`: Debian
# packages, munge authentication, no systemd (the daemons run in the background).
#
#   tools/slurm_single_node.sh up       install the packages if needed, write the configuration,
#                                       start munged, slurmctld and slurmd, wait until the node
#                                       takes jobs
#   tools/slurm_single_node.sh down     cancel every job, wait for the queue to drain (running
#                                       jobs outlive slurmd), stop the daemons, remove the
#                                       configuration written by `up`
#   tools/slurm_single_node.sh status   sinfo and squeue
#
# Needs root (packages, /etc/slurm/slurm.conf, daemons). `up` exits with status 77 ("skipped")
# and says why when Slurm cannot be brought up here (not root, no apt-get, packages not
# installable), so callers can report a skip rather than a pass.
#
# Settings (measured on a 2-core Debian 12 container, Slurm 22.05):
#   ProctrackType=proctrack/linuxproc, TaskPlugin=task/none   no cgroups / systemd needed
#   SelectType=select/cons_tres, SelectTypeParameters=CR_CPU  CPUs only: tracking memory
#                                                             serialises jobs without --mem
#   SchedulerParameters=batch_sched_delay=0                   short arrays finish sooner
# Without slurmdbd `sacct` has no data: use `squeue -t all` or `scontrol show job`.
set -uo pipefail

STATE=${TREAD_SLURM_STATE:-/var/tmp/tread-slurm}
CONF=/etc/slurm/slurm.conf
MARK="# written by tools/slurm_single_node.sh"

skip() {
    echo "SKIP: single-node Slurm not available: $*" >&2
    exit 77
}

write_conf() {
    local host cpus mem
    host=$(hostname -s)
    cpus=$(nproc)
    mem=$(awk '/MemTotal/ { printf "%d", $2 / 1024 * 0.9 }' /proc/meminfo)
    if [ -e "$CONF" ] && ! grep -qF "$MARK" "$CONF"; then
        skip "$CONF exists and was not written by this script (not touching a real cluster's configuration)"
    fi
    mkdir -p /etc/slurm "$STATE"/{ctld,d,log}
    cat > "$CONF" <<EOF
$MARK
ClusterName=tread-test
SlurmctldHost=$host
AuthType=auth/munge
CryptoType=crypto/munge
SlurmUser=root
SlurmdUser=root
SlurmctldPort=6817
SlurmdPort=6818
StateSaveLocation=$STATE/ctld
SlurmdSpoolDir=$STATE/d
SlurmctldPidFile=$STATE/slurmctld.pid
SlurmdPidFile=$STATE/slurmd.pid
SlurmctldLogFile=$STATE/log/slurmctld.log
SlurmdLogFile=$STATE/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerParameters=batch_sched_delay=0
ReturnToService=2
MpiDefault=none
JobCompType=jobcomp/none
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
MinJobAge=300
KillWait=30
NodeName=$host CPUs=$cpus RealMemory=$mem State=UNKNOWN
PartitionName=debug Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
}

wait_for() { # seconds, command...
    local t=$1
    shift
    for _ in $(seq $((t * 5))); do
        "$@" > /dev/null 2>&1 && return 0
        sleep 0.2
    done
    return 1
}

up() {
    [ "$(id -u)" = 0 ] || skip "needs root (packages, $CONF, daemons)"
    if ! command -v slurmctld > /dev/null || ! command -v slurmd > /dev/null \
        || ! command -v sbatch > /dev/null || ! command -v munged > /dev/null; then
        command -v apt-get > /dev/null || skip "no apt-get to install slurmctld slurmd slurm-client munge"
        echo "installing slurmctld slurmd slurm-client munge ..." >&2
        if ! DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends \
            slurmctld slurmd slurm-client munge > "$STATE.apt.log" 2>&1; then
            (DEBIAN_FRONTEND=noninteractive apt-get update > /dev/null 2>&1 \
                && DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends \
                    slurmctld slurmd slurm-client munge > "$STATE.apt.log" 2>&1) \
                || skip "apt-get install failed (see $STATE.apt.log)"
        fi
    fi
    write_conf
    # munge: key, runtime directory, daemon (as the munge user).
    if [ ! -s /etc/munge/munge.key ]; then
        (command -v mungekey > /dev/null && mungekey --create --force) \
            || dd if=/dev/urandom of=/etc/munge/munge.key bs=1024 count=1 2> /dev/null
        chown munge:munge /etc/munge/munge.key
        chmod 600 /etc/munge/munge.key
    fi
    mkdir -p /run/munge /var/log/munge /var/lib/munge
    chown munge:munge /run/munge /var/log/munge /var/lib/munge
    if ! munge -n 2> /dev/null | unmunge > /dev/null 2>&1; then
        runuser -u munge -- /usr/sbin/munged || skip "munged does not start"
        wait_for 10 sh -c 'munge -n | unmunge' || skip "munge does not authenticate"
    fi
    if ! scontrol ping 2> /dev/null | grep -q UP; then
        slurmctld -D > "$STATE/log/slurmctld.out" 2>&1 &
        wait_for 20 sh -c 'scontrol ping | grep -q UP' \
            || skip "slurmctld does not start (see $STATE/log/)"
    fi
    if ! pgrep -x slurmd > /dev/null; then
        slurmd -D > "$STATE/log/slurmd.out" 2>&1 &
    fi
    local host
    host=$(hostname -s)
    wait_for 30 sh -c "sinfo -h -n $host -o %t | grep -Eq '^(idle|mix|alloc)'" || {
        scontrol update nodename="$host" state=resume > /dev/null 2>&1
        wait_for 10 sh -c "sinfo -h -n $host -o %t | grep -Eq '^(idle|mix|alloc)'" \
            || skip "the node does not become idle: $(sinfo -h -n "$host" -o '%t %E')"
    }
    echo "slurm up: $(sinfo -h -o '%P %D nodes %c cpus %t')" >&2
}

down() {
    if command -v scancel > /dev/null && scontrol ping 2> /dev/null | grep -q UP; then
        scancel --user="$(id -un)" 2> /dev/null
        # Running jobs outlive slurmd: wait for the queue to drain first.
        wait_for 60 sh -c '[ -z "$(squeue -h)" ]' || echo "warning: jobs still queued: $(squeue -h)" >&2
    fi
    for d in slurmd slurmctld; do
        if [ -f "$STATE/$d.pid" ]; then
            kill "$(cat "$STATE/$d.pid")" 2> /dev/null
        fi
    done
    wait_for 15 sh -c '! pgrep -x slurmd && ! pgrep -x slurmctld' \
        || echo "warning: Slurm daemons still running" >&2
    if [ -f /run/munge/munged.pid ]; then
        kill "$(cat /run/munge/munged.pid)" 2> /dev/null
    fi
    if [ -f "$CONF" ] && grep -qF "$MARK" "$CONF"; then
        rm -f "$CONF"
    fi
    rm -rf "$STATE"
    echo "slurm down" >&2
}

case "${1:-}" in
    up) up ;;
    down) down ;;
    status)
        sinfo
        squeue -t all
        ;;
    *)
        echo "usage: $0 up|down|status" >&2
        exit 2
        ;;
esac
