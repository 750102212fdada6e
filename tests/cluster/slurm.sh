#!/bin/sh
# A one-node Slurm on this machine, from Debian's packages, for tests/cluster/.
#
#   tests/cluster/slurm.sh up [DIR]     install slurm-wlm and munge if missing (root, apt-get),
#                                       start munged, slurmctld and slurmd with every file
#                                       (config, key, socket, state, logs) under DIR
#   tests/cluster/slurm.sh env [DIR]    print the environment a client needs (SLURM_CONF=...)
#   tests/cluster/slurm.sh down [DIR]   stop the daemons started by `up` (by their pid files)
#
# DIR defaults to /tmp/flyover-slurm. Outside DIR only the packages and one symlink are
# written: /etc/slurm/slurm.conf -> DIR/slurm.conf, removed by `down`. It is needed because
# the executor's job step (snakemake-executor-plugin-slurm-jobstep) drops every SLURM_*
# variable, SLURM_CONF too, before its `srun`, which then finds no configuration ("srun:
# fatal: Could not establish a configuration source"). A machine that already has an
# /etc/slurm/slurm.conf of its own is refused (exit 2), never changed. The daemons use their
# own ports (FLYOVER_SLURM_PORT, default 16817, and the next three) and munge socket.
# No accounting database by default: the Snakemake executor is told to ask squeue for job
# states (MinJobAge = 1 h keeps finished jobs visible to it); see README "Running on a
# cluster". FLYOVER_SLURM_ACCOUNTING=1 adds one (slurmdbd and MariaDB, installed if missing,
# the database in DIR/db on a private port): sacct then answers, as on most clusters, with
# each job's MaxRSS and TotalCPU.
# Exit status 2 with one line on stderr when Slurm cannot be installed or started here.
set -eu
cmd=${1:-}
D=${2:-/tmp/flyover-slurm}
PORT=${FLYOVER_SLURM_PORT:-16817}
ACCOUNTING=${FLYOVER_SLURM_ACCOUNTING:-0}
NODE=$(hostname -s)

fail() { echo "slurm.sh: $*" >&2; exit 2; }

install() {
    command -v slurmctld >/dev/null && command -v munged >/dev/null && return 0
    [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null ||
        fail "slurm-wlm and munge are not installed, and apt-get as root is not available"
    echo "slurm.sh: installing slurm-wlm and munge (apt-get)" >&2
    { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq slurm-wlm munge; } \
        >"$D/apt.log" 2>&1 || fail "apt-get install slurm-wlm munge failed (see $D/apt.log)"
}

install_accounting() {
    command -v slurmdbd >/dev/null && command -v mariadbd >/dev/null && return 0
    [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null ||
        fail "slurmdbd and mariadb-server are not installed, and apt-get as root is not available"
    echo "slurm.sh: installing slurmdbd and mariadb-server (apt-get)" >&2
    { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq slurmdbd mariadb-server; } \
        >"$D/apt-accounting.log" 2>&1 ||
        fail "apt-get install slurmdbd mariadb-server failed (see $D/apt-accounting.log)"
}

# MariaDB in DIR/db (socket DIR/db/mysql.sock, TCP 127.0.0.1:PORT+2), slurmdbd on PORT+3
accounting_up() {
    install_accounting
    if [ ! -d "$D/db/mysql" ]; then
        mariadb-install-db --no-defaults --datadir="$D/db" --user=root --skip-test-db \
            >"$D/log/mariadb-install.log" 2>&1 || fail "mariadb-install-db failed (see $D/log/mariadb-install.log)"
    fi
    mariadbd --no-defaults --datadir="$D/db" --socket="$D/db/mysql.sock" --bind-address=127.0.0.1 \
        --port=$((PORT + 2)) --pid-file="$D/db/mariadb.pid" --user=root \
        --log-error="$D/log/mariadb.log" >/dev/null 2>&1 &
    i=0
    until mariadb --no-defaults --socket="$D/db/mysql.sock" -e "select 1" >/dev/null 2>&1; do
        i=$((i + 1)); [ $i -le 60 ] || fail "MariaDB did not start in 60 s (see $D/log/mariadb.log)"; sleep 1
    done
    mariadb --no-defaults --socket="$D/db/mysql.sock" -e "
        CREATE USER IF NOT EXISTS 'slurm'@'127.0.0.1' IDENTIFIED BY 'flyover-test';
        GRANT ALL ON slurm_acct_db.* TO 'slurm'@'127.0.0.1';" ||
        fail "cannot create the slurm database user"
    cat >"$D/slurmdbd.conf" <<CONF
AuthType=auth/munge
AuthInfo=socket=$D/munge/munge.socket
DbdHost=localhost
DbdAddr=127.0.0.1
DbdPort=$((PORT + 3))
SlurmUser=root
PidFile=$D/slurmdbd.pid
LogFile=$D/log/slurmdbd.log
StorageType=accounting_storage/mysql
StorageHost=127.0.0.1
StoragePort=$((PORT + 2))
StorageUser=slurm
StoragePass=flyover-test
StorageLoc=slurm_acct_db
CONF
    chmod 600 "$D/slurmdbd.conf"
    # slurmdbd reads slurmdbd.conf beside $SLURM_CONF
    slurmdbd || fail "slurmdbd did not start (see $D/log/slurmdbd.log)"
    i=0
    until sacctmgr -n list cluster >/dev/null 2>&1; do
        i=$((i + 1)); [ $i -le 60 ] || fail "slurmdbd did not answer in 60 s (see $D/log/slurmdbd.log)"; sleep 1
    done
    sacctmgr -i add cluster flyover-test >/dev/null 2>&1 || true
}

config() {
    cpus=$(nproc)
    # what the node offers jobs: the machine's memory less 1 GB for the rest
    mem=$(awk '/MemTotal/ {print int($2 / 1024) - 1024}' /proc/meminfo)
    cat >"$D/slurm.conf" <<CONF
ClusterName=flyover-test
SlurmctldHost=$NODE(127.0.0.1)
SlurmctldPort=$PORT
SlurmdPort=$((PORT + 1))
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$D/munge/munge.socket
CredType=cred/munge
StateSaveLocation=$D/state
SlurmdSpoolDir=$D/spool
SlurmctldPidFile=$D/slurmctld.pid
SlurmdPidFile=$D/slurmd.pid
SlurmctldLogFile=$D/log/slurmctld.log
SlurmdLogFile=$D/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
SchedulerType=sched/backfill
ReturnToService=2
MinJobAge=3600
MpiDefault=none
$(if [ "$ACCOUNTING" = 1 ]; then cat <<ACC
JobAcctGatherType=jobacct_gather/linux
JobAcctGatherFrequency=1
AccountingStorageType=accounting_storage/slurmdbd
AccountingStorageHost=127.0.0.1
AccountingStoragePort=$((PORT + 3))
AccountingStoragePass=$D/munge/munge.socket
ACC
else cat <<ACC
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
ACC
fi)
JobCompType=jobcomp/none
NodeName=$NODE NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$mem State=UNKNOWN
PartitionName=debug Nodes=$NODE Default=YES MaxTime=INFINITE State=UP
CONF
}

up() {
    mkdir -p "$D/munge" "$D/state" "$D/spool" "$D/log"
    install
    [ -f "$D/slurmctld.pid" ] && kill -0 "$(cat "$D/slurmctld.pid")" 2>/dev/null &&
        fail "a Slurm of $D is already running (tests/cluster/slurm.sh down $D)"
    chmod 700 "$D/munge"
    [ -f "$D/munge/munge.key" ] || dd if=/dev/urandom of="$D/munge/munge.key" bs=1024 count=1 2>/dev/null
    chmod 400 "$D/munge/munge.key"
    munged --force --key-file="$D/munge/munge.key" --socket="$D/munge/munge.socket" \
        --pid-file="$D/munge/munged.pid" --log-file="$D/munge/munged.log" \
        --seed-file="$D/munge/munged.seed" || fail "munged did not start (see $D/munge/munged.log)"
    config
    if [ -L /etc/slurm/slurm.conf ] && [ "$(readlink /etc/slurm/slurm.conf)" = "$D/slurm.conf" ]; then
        :
    elif [ -e /etc/slurm/slurm.conf ] || [ -L /etc/slurm/slurm.conf ]; then
        down; fail "/etc/slurm/slurm.conf exists (this machine has a Slurm of its own): not touched"
    else
        mkdir -p /etc/slurm && ln -s "$D/slurm.conf" /etc/slurm/slurm.conf ||
            { down; fail "cannot link /etc/slurm/slurm.conf to $D/slurm.conf"; }
    fi
    export SLURM_CONF="$D/slurm.conf"
    if [ "$ACCOUNTING" = 1 ]; then accounting_up; fi
    slurmctld -f "$SLURM_CONF" || fail "slurmctld did not start (see $D/log/slurmctld.log)"
    # jobs run niced: the machine is shared
    nice -n 10 slurmd -f "$SLURM_CONF" -N "$NODE" || fail "slurmd did not start (see $D/log/slurmd.log)"
    i=0
    until sinfo -h -N -o %t 2>/dev/null | grep -qx idle; do
        i=$((i + 1))
        [ $i -le 60 ] || fail "the node did not come up in 60 s: $(sinfo -h -N -o '%t %E' 2>&1 | head -1)"
        sleep 1
    done
    echo "slurm.sh: one-node Slurm up in $D (SLURM_CONF=$SLURM_CONF)" >&2
}

down() {
    for f in "$D/slurmd.pid" "$D/slurmctld.pid" "$D/slurmdbd.pid" "$D/db/mariadb.pid" "$D/munge/munged.pid"; do
        [ -f "$f" ] || continue
        pid=$(cat "$f")
        kill "$pid" 2>/dev/null || true
        i=0
        while kill -0 "$pid" 2>/dev/null && [ $i -lt 20 ]; do sleep 0.5; i=$((i + 1)); done
        rm -f "$f"
    done
    if [ -L /etc/slurm/slurm.conf ] && [ "$(readlink /etc/slurm/slurm.conf)" = "$D/slurm.conf" ]; then
        rm -f /etc/slurm/slurm.conf
    fi
}

case "$cmd" in
    up) up ;;
    env) echo "SLURM_CONF=$D/slurm.conf" ;;
    down) down ;;
    *) echo "usage: tests/cluster/slurm.sh up|env|down [DIR]" >&2; exit 2 ;;
esac
