# A single-node Slurm cluster for scripts/test-slurm and scripts/bench-slurm, sourced by them
# (`source scripts/slurm-cluster.sh ARGS...`, SELF the calling script's absolute path): installs Debian's slurmctld,
# slurmd and slurm-client when missing, runs the calling script again inside a network
# namespace of its own (unshare --net), and there starts slurmctld and slurmd in the
# foreground of the script, stopped (and their directory $D removed) when it exits.
#
# In the namespace the only addresses are loopback's and one on a veth pair whose two ends are
# both inside it (Slurm resolves its hosts with AI_ADDRCONFIG, which ignores loopback): nothing
# reaches or is reachable from any other machine. auth/none and cred/none need no munge; no
# systemd is involved. Needs root (CI runs as root), or sudo without a password.

as_root() {
    if [ "$(id -u)" = 0 ]; then "$@"
    elif command -v sudo >/dev/null && sudo -n true 2>/dev/null; then sudo "$@"
    else
        echo "$(basename "$0"): this needs root ($*): run as root, or with password-less sudo" >&2
        exit 1
    fi
}

if [ -z "${PENDULA_SLURM_NETNS:-}" ]; then
    if ! command -v slurmctld >/dev/null || ! command -v slurmd >/dev/null || ! command -v sbatch >/dev/null; then
        echo "== installing Debian's Slurm packages (slurmctld slurmd slurm-client)"
        export DEBIAN_FRONTEND=noninteractive
        as_root apt-get install -y -q --no-install-recommends slurmctld slurmd slurm-client >/dev/null 2>&1 \
            || { as_root apt-get update -q >/dev/null && as_root apt-get install -y -q --no-install-recommends slurmctld slurmd slurm-client >/dev/null; }
    fi
    if [ "${PENDULA_SLURM_SETUP_ONLY:-}" = 1 ]; then exit 0; fi
    # The same script again, inside a new network namespace.
    as_root env PENDULA_SLURM_NETNS=1 unshare --net bash "${SELF:-$0}" "$@"
    exit
fi

# ---- inside the namespace -------------------------------------------------------------
ip link set lo up
ip link add pendula0 type veth peer name pendula1
ip addr add 192.0.2.1/32 dev pendula0   # TEST-NET-1: a documentation address, routed nowhere
ip link set pendula0 up
ip link set pendula1 up

HOST=$(hostname -s)
D=$(mktemp -d /tmp/pendula-slurm.XXXXXX)
chmod 755 "$D"
export SLURM_CONF=$D/slurm.conf
PIDS=()
cleanup() {
    local rc=$?
    for p in "${PIDS[@]}"; do kill "$p" 2>/dev/null || true; done
    wait 2>/dev/null || true
    if [ "$rc" != 0 ]; then
        echo "$(basename "$0"): FAILED (exit $rc); the daemons' logs:" >&2
        tail -n 20 "$D"/slurmctld.log "$D"/slurmd.log "$D"/work/*.shards/*.out 2>/dev/null >&2 || true
    fi
    rm -rf "$D"
    exit "$rc"
}
trap cleanup EXIT
mkdir -p "$D/state" "$D/spool" "$D/work"
cat > "$SLURM_CONF" <<EOF
ClusterName=pendula-test
SlurmctldHost=$HOST(127.0.0.1)
SlurmctldPort=16817
SlurmdPort=16818
AuthType=auth/none
CredType=cred/none
SlurmUser=root
SlurmdUser=root
StateSaveLocation=$D/state
SlurmdSpoolDir=$D/spool
SlurmctldPidFile=$D/slurmctld.pid
SlurmdPidFile=$D/slurmd.pid
SlurmctldLogFile=$D/slurmctld.log
SlurmdLogFile=$D/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
MpiDefault=none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/builtin
# Pending jobs (the merge waiting on the array) are looked at every second, not every 60 s,
# and a cancelled shard is killed 2 s after SIGTERM, not 30 s.
SchedulerParameters=sched_interval=1
KillWait=2
ReturnToService=2
JobCompType=jobcomp/none
AccountingStorageType=accounting_storage/none
NodeName=$HOST NodeAddr=127.0.0.1 NodeHostname=$HOST CPUs=$(nproc) State=UNKNOWN
PartitionName=test Nodes=ALL Default=YES MaxTime=INFINITE State=UP
EOF
slurmctld -D -i >/dev/null 2>&1 &
PIDS+=($!)
slurmd -D >/dev/null 2>&1 &
PIDS+=($!)
for _ in $(seq 60); do
    [ "$(sinfo -h -o %T 2>/dev/null)" = idle ] && break
    sleep 0.5
done
[ "$(sinfo -h -o %T 2>/dev/null)" = idle ] || { echo "$(basename "$0"): the node did not come up" >&2; exit 1; }
echo "== single-node Slurm up ($(sinfo -V), node $HOST at 127.0.0.1, $(nproc) CPUs)"

