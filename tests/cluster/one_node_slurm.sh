#!/bin/sh
# A one-node Slurm cluster in a scratch folder, on localhost only, for qnav's tests and
# docs/cluster.md: munged with its own key and socket, slurmctld and slurmd (SlurmUser
# root, proctrack/linuxproc, no systemd, no cgroups, no accounting), every address
# 127.0.0.1 (SlurmctldHost=localhost, NodeAddr=127.0.0.1) and CommunicationParameters=
# NoInAddrAny,NoCtldInAddrAny so both daemons listen on 127.0.0.1 only.
#
#   . tests/cluster/one_node_slurm.sh; cluster_up DIR   # sets SLURM_CONF; returns 77 with
#       the reason on stderr when it cannot try (not root, a program missing), 1 with the
#       daemon's log when a daemon does not come up
#   cluster_down                                        # stops every daemon by its PID
# cluster_up leaves the daemons' PIDs in CLUSTER_PIDS; callers trap cluster_down on exit.
# Its variables are prefixed cl_ (sh has no locals).

CLUSTER_PIDS=""

cluster_skip() { echo "one-node Slurm cluster not started: $*" >&2; return 77; }
cluster_fail() { echo "one-node Slurm cluster failed: $*" >&2; return 1; }

# A free TCP port on 127.0.0.1 from a range few services use.
cluster_free_port() {
    cl_p=$1
    while ss -ltn 2>/dev/null | awk '{print $4}' | grep -q ":$cl_p\$"; do cl_p=$((cl_p + 1)); done
    echo "$cl_p"
}

cluster_wait_for() { # SECONDS COMMAND...: until COMMAND succeeds; 1 on timeout
    cl_t=$1; shift
    while [ "$cl_t" -gt 0 ]; do
        if "$@" >/dev/null 2>&1; then return 0; fi
        sleep 1; cl_t=$((cl_t - 1))
    done
    return 1
}

cluster_up() {
    cl_dir=$1
    [ "$(id -u)" = 0 ] || { cluster_skip "not root (slurmd must run as root; CI runs as root)"; return 77; }
    for cl_b in munged mungekey slurmctld slurmd sbatch squeue sinfo scontrol ss; do
        command -v "$cl_b" >/dev/null 2>&1 || [ -x "/usr/sbin/$cl_b" ] ||
            { cluster_skip "$cl_b not installed (Debian 12: slurm-wlm munge iproute2, tools/debian-packages.txt)"; return 77; }
    done
    PATH=$PATH:/usr/sbin
    mkdir -p "$cl_dir/state" "$cl_dir/spool" "$cl_dir/munge" && chmod 700 "$cl_dir/munge" || return 1
    mungekey -c -k "$cl_dir/munge/munge.key" >/dev/null 2>&1 || { cluster_fail "mungekey -c failed"; return 1; }
    munged -F -f --socket="$cl_dir/munge/munge.sock" --key-file="$cl_dir/munge/munge.key" \
        --pid-file="$cl_dir/munge/munged.pid" --log-file="$cl_dir/munge/munged.log" --seed-file="$cl_dir/munge/munged.seed" \
        >"$cl_dir/munge/munged.out" 2>&1 &
    CLUSTER_PIDS="$!"
    cluster_wait_for 10 test -S "$cl_dir/munge/munge.sock" ||
        { cluster_fail "munged did not start: $(tail -n 1 "$cl_dir/munge/munged.out" "$cl_dir/munge/munged.log" 2>/dev/null | tr '\n' ' ')"; return 1; }
    cl_host=$(hostname -s)
    # ports from the process id, so two test runs at once are unlikely to race for one
    cl_ctld_port=$(cluster_free_port $((20000 + ($$ % 4000) * 2)))
    cl_slurmd_port=$(cluster_free_port $((cl_ctld_port + 1)))
    cat >"$cl_dir/slurm.conf" <<CONF
ClusterName=qnavtest
SlurmctldHost=localhost
SlurmctldPort=$cl_ctld_port
SlurmdPort=$cl_slurmd_port
CommunicationParameters=NoInAddrAny,NoCtldInAddrAny
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$cl_dir/munge/munge.sock
StateSaveLocation=$cl_dir/state
SlurmdSpoolDir=$cl_dir/spool
SlurmctldPidFile=$cl_dir/slurmctld.pid
SlurmdPidFile=$cl_dir/slurmd.pid
SlurmctldLogFile=$cl_dir/slurmctld.log
SlurmdLogFile=$cl_dir/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
MpiDefault=none
ReturnToService=2
SlurmdTimeout=60
NodeName=qnavnode NodeAddr=127.0.0.1 NodeHostname=$cl_host CPUs=$(nproc) State=UNKNOWN
PartitionName=qnav Nodes=qnavnode Default=YES MaxTime=INFINITE State=UP
CONF
    export SLURM_CONF="$cl_dir/slurm.conf"
    slurmctld -D -i -f "$SLURM_CONF" >"$cl_dir/slurmctld.out" 2>&1 &
    CLUSTER_PIDS="$CLUSTER_PIDS $!"
    cluster_wait_for 20 scontrol ping ||
        { cluster_fail "slurmctld did not answer: $(tail -n 2 "$cl_dir/slurmctld.log" "$cl_dir/slurmctld.out" 2>/dev/null | tr '\n' ' ')"; return 1; }
    slurmd -D -N qnavnode -f "$SLURM_CONF" >"$cl_dir/slurmd.out" 2>&1 &
    CLUSTER_PIDS="$CLUSTER_PIDS $!"
    cluster_wait_for 30 sh -c 'sinfo -h -o %t | grep -qx idle' ||
        { cluster_fail "slurmd did not register: $(tail -n 2 "$cl_dir/slurmd.log" "$cl_dir/slurmd.out" 2>/dev/null | tr '\n' ' ')"; return 1; }
    return 0
}

cluster_down() {
    for cl_p in $CLUSTER_PIDS; do kill "$cl_p" 2>/dev/null; done
    for cl_p in $CLUSTER_PIDS; do
        cl_i=0
        while kill -0 "$cl_p" 2>/dev/null && [ $cl_i -lt 50 ]; do sleep 0.1; cl_i=$((cl_i + 1)); done
        kill -9 "$cl_p" 2>/dev/null
    done
    CLUSTER_PIDS=""
}
