#!/usr/bin/env bash
# A throw-away, single-node Slurm cluster on this machine, for tests of `aerotrack bench --executor slurm`
# (issue 25): a real slurmctld + slurmd + munged, so sbatch/squeue/scancel behave as on a real cluster (job
# arrays with a %N throttle, time limits, scancel, rejected submissions). Nothing system-wide is touched:
# no /etc/slurm, /etc/munge, /run/munge, no systemd; everything lives in DIR.
#
# usage: scripts/slurm_cluster.sh start DIR   # prints `export SLURM_CONF=DIR/slurm.conf` as its last line
#        scripts/slurm_cluster.sh stop DIR    # cancels jobs, stops the daemons (TERM, then KILL after 10 s),
#                                               kills leftover slurmstepd/job processes, keeps DIR (logs) in place
#        then: SLURM_CONF=DIR/slurm.conf sbatch ... / squeue ... / scancel ...
# `start` is idempotent (says so if DIR's cluster already runs); `stop` is idempotent (nothing running: fine).
#
# DIR holds: munge/ (munge.key 0400, socket, pid, log, seed), slurm.conf, state/ (StateSaveLocation), spool/
# (SlurmdSpoolDir), log/ (slurmctld.log, slurmd.log, daemons' stdout), run/ (pid files).
#
# The settings that matter, and why:
#   munged --socket=DIR/munge/... --force     our own munged with a fresh key; --force because we run as root
#   AuthInfo=socket=DIR/munge/munge.socket    clients (sbatch/squeue/scancel) and daemons find our munged via
#                                             slurm.conf alone, so SLURM_CONF is the only variable a caller sets;
#                                             the same socket is used by CredType=cred/munge
#   SlurmctldHost=$(hostname -s)(127.0.0.1)   the name must be this host's (slurmctld checks it); the address
#   NodeAddr=127.0.0.1                        keeps all traffic on loopback; slurmd runs with -N NODE.
#                                             (slurmd binds NodeAddr via CommunicationParameters=NoInAddrAny; Slurm
#                                             22.05's slurmctld always listens on INADDR_ANY:SlurmctldPort, but a
#                                             request still needs DIR's munge key)
#   SlurmctldPort/SlurmdPort                  derived from a hash of DIR in 20000-39999, first free pair taken
#   ProctrackType=proctrack/linuxproc, TaskPlugin=task/none, no cgroup.conf: works in containers without cgroups
#   AccountingStorageType=none, JobAcctGatherType=none: no slurmdbd
#   SelectType=select/cons_tres, CR_Core_Memory: one core per task (so %N throttles are what limits
#             concurrency, up to the node's CPUs) and --mem is checked against RealMemory (MemTotal - 10%,
#             at least 512 MiB margin); DefMemPerCPU = RealMemory/CPUs so a job without --mem does not take
#             the whole node
#   SlurmdParameters=config_overrides        trust CPUs/RealMemory from slurm.conf (containers report odd topology)
#   EnforcePartLimits=ALL                     a job the node can never run (-c above CPUs, --mem above RealMemory)
#                                             is rejected by sbatch instead of pending forever
#   ReturnToService=2                         the node comes back to idle by itself after a slurmd restart
#   MinJobAge=2                               `squeue -j ID` lists a job only while pending/running/completing;
#                                             its record is purged ~10 s after it ends, after which
#                                             `squeue -j ID` fails (rc 1, "Invalid job id specified")
#   KillWait=2, OverTimeLimit=0               a job past --time gets SIGTERM, then SIGKILL 2 s later (slurmctld
#                                             checks limits every ~30 s and --time's minimum is 1 minute, so a
#                                             --time=1 job dies 60-90 s after it started)
#   SchedulerParameters=batch_sched_delay=0,sched_interval=1,bf_interval=1, CompleteWait=0: pending jobs and
#             array tasks start within ~1-2 s of a free slot (slurmctld schedules from a 1 s background loop)
#   slurmctld -c, FirstJobId                  each start begins with no jobs (an earlier run that was not
#                                             stopped cleanly would otherwise have its jobs requeued and rerun);
#                                             FirstJobId continues after the highest id in DIR's slurmctld.log
#   InactiveLimit=0, SlurmdTimeout=30, MessageTimeout=10
# Env: SLURM_CLUSTER_CPUS overrides CPUs (default: nproc). Sockets are unix sockets: DIR must be short enough
# (< ~90 characters) for DIR/munge/munge.socket.
set -euo pipefail

usage() {
  echo "usage: $0 start|stop DIR" >&2
  exit 2
}
(($# == 2)) || usage
cmd=$1
[[ -n $2 ]] || usage
dir=$(realpath -m -- "$2")

conf=$dir/slurm.conf
munge_dir=$dir/munge
socket=$munge_dir/munge.socket
run=$dir/run
logs=$dir/log
node=$(hostname -s)
export SLURM_CONF=$conf
# Clients must not pick up a caller's job context or another cluster's settings.
unset SLURM_JOB_ID SLURM_JOBID SLURM_ARRAY_JOB_ID SLURM_ARRAY_TASK_ID

# true if pid runs (a zombie waiting for init to reap it counts as gone)
running() { # pid
  local stat
  stat=$(cat "/proc/$1/stat" 2>/dev/null) || return 1
  stat=${stat##*) }
  [[ ${stat:0:1} != Z ]]
}

# pid of a daemon from its pid file if it runs and is that daemon, else nothing
alive_pid() { # name pidfile
  local pid comm
  [[ -s $2 ]] || return 1
  pid=$(tr -dc 0-9 <"$2")
  [[ -n $pid ]] || return 1
  comm=$(cat "/proc/$pid/comm" 2>/dev/null) || return 1
  [[ $comm == "$1"* ]] && running "$pid" || return 1
  echo "$pid"
}

port_free() { # port
  ! ss -Hltn 2>/dev/null | awk '{print $4}' | grep -Eq "[:.]$1\$"
}

node_state() { timeout 5 sinfo -h -n "$node" -o %T 2>/dev/null | head -n1; }

# TERM the daemons named by "name:pidfile" arguments together, wait up to 10 s, then KILL the rest
stop_daemons() {
  local spec pid i left
  local -a pids=() names=()
  for spec in "$@"; do
    pid=$(alive_pid "${spec%%:*}" "${spec#*:}") || continue
    kill -TERM "$pid" 2>/dev/null || continue
    pids+=("$pid")
    names+=("${spec%%:*}")
  done
  for ((i = 0; i < 150; i++)); do # 10 s, then 5 s after SIGKILL
    left=0
    for pid in "${pids[@]}"; do
      running "$pid" && left=1
    done
    ((left)) || return 0
    if ((i == 100)); then
      echo "${names[*]} (pids ${pids[*]}): still running 10 s after SIGTERM, sending SIGKILL" >&2
      kill -KILL "${pids[@]}" 2>/dev/null || true
    fi
    sleep 0.1
  done
}

# Processes of this cluster's jobs that outlive slurmd: slurmstepd and the job's own processes carry
# SLURM_CONF=DIR/slurm.conf in their environment (slurmd is started with it; jobs get it from slurmstepd).
# Callers that merely export SLURM_CONF are spared: a job process also has SLURMD_NODENAME and SLURM_JOB_ID.
cluster_strays() {
  local p env comm stat fields candidates ancestors=" " a=$$
  while [[ $a -gt 1 ]]; do # never this script nor whoever runs it
    ancestors+="$a "
    stat=$(cat "/proc/$a/stat" 2>/dev/null) || break
    read -ra fields <<<"${stat##*) }"
    a=${fields[1]}
  done
  candidates=$(grep -lzsxF "SLURM_CONF=$conf" /proc/[0-9]*/environ 2>/dev/null | cut -d/ -f3 || true)
  while read -r p; do
    [[ -n $p && $ancestors != *" $p "* ]] || continue
    env=$(tr '\0' '\n' 2>/dev/null <"/proc/$p/environ") || continue
    comm=$(cat "/proc/$p/comm" 2>/dev/null) || continue
    running "$p" || continue
    if [[ $comm == slurmstepd* ]] ||
      { grep -qxF "SLURMD_NODENAME=$node" <<<"$env" && grep -q '^SLURM_JOB_ID=' <<<"$env"; }; then
      echo "$p"
    fi
  done <<<"$candidates"
}

do_stop() {
  local ids i strays
  if alive_pid slurmctld "$run/slurmctld.pid" >/dev/null && alive_pid munged "$munge_dir/munged.pid" >/dev/null; then
    # Cancel whatever still runs, so no slurmstepd/job outlives the cluster.
    ids=$(timeout 10 squeue -h -o %F 2>/dev/null | sort -u | tr '\n' ' ') || ids=
    if [[ -n ${ids// /} ]]; then
      # shellcheck disable=SC2086
      timeout 10 scancel $ids 2>/dev/null || true
      for ((i = 0; i < 150; i++)); do # 15 s: KillWait (2 s) + epilog
        [[ -z $(timeout 10 squeue -h -o %i 2>/dev/null) ]] && break
        sleep 0.1
      done
    fi
  fi
  stop_daemons "slurmd:$run/slurmd.pid" "slurmctld:$run/slurmctld.pid"
  stop_daemons "munged:$munge_dir/munged.pid" # last: the slurm daemons talk through it until they exit
  strays=$(cluster_strays)
  if [[ -n $strays ]]; then
    # shellcheck disable=SC2086
    kill -TERM $strays 2>/dev/null || true
    sleep 1
    strays=$(cluster_strays)
    # shellcheck disable=SC2086
    [[ -z $strays ]] || kill -KILL $strays 2>/dev/null || true
  fi
  rm -f "$run"/*.pid "$munge_dir/munged.pid"
}

show_logs() {
  local f
  for f in "$munge_dir/munged.log" "$logs/slurmctld.log" "$logs/slurmd.log" "$logs"/*.out; do
    [[ -s $f ]] || continue
    echo "---- last lines of $f" >&2
    tail -n 25 "$f" >&2
  done
}

write_conf() {
  local cpus mem_kb real_mem margin ctld_port slurmd_port h tries last_id
  cpus=${SLURM_CLUSTER_CPUS:-$(nproc)}
  mem_kb=$(awk '/^MemTotal:/ {print $2}' /proc/meminfo)
  real_mem=$((mem_kb / 1024))
  margin=$((real_mem / 10))
  ((margin >= 512)) || margin=512
  real_mem=$((real_mem - margin))
  ((real_mem >= 256)) || real_mem=256
  h=$(cksum <<<"$dir" | awk '{print $1}')
  ctld_port=$((20000 + (h % 10000) * 2))
  for ((tries = 0; tries < 200; tries++)); do
    slurmd_port=$((ctld_port + 1))
    port_free "$ctld_port" && port_free "$slurmd_port" && break
    ctld_port=$((ctld_port + 2))
    ((ctld_port < 40000)) || ctld_port=20000
  done
  # slurmctld starts with -c (no jobs replayed from an earlier run that crashed); job ids go on from the
  # highest one its log names (JobId=N, or JobId=A_T(N) for an array task), so log names stay unique per DIR
  last_id=$(grep -ohE 'JobId=[0-9]+(_[0-9]+\([0-9]+\))?' "$logs/slurmctld.log" 2>/dev/null |
    grep -oE '[0-9]+' | sort -n | tail -n1 || true)
  : >"$dir/plugstack.conf"
  cat >"$conf" <<EOF
# Generated by scripts/slurm_cluster.sh for a throw-away test cluster; see that script.
ClusterName=aerotrack-test
FirstJobId=$((${last_id:-0} + 1))
SlurmctldHost=$node(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
CommunicationParameters=NoInAddrAny
AuthType=auth/munge
AuthInfo=socket=$socket
CredType=cred/munge
SlurmUser=$(id -un)
SlurmdUser=$(id -un)
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$run/slurmctld.pid
SlurmdPidFile=$run/slurmd.pid
SlurmctldLogFile=$logs/slurmctld.log
SlurmdLogFile=$logs/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
PlugStackConfig=$dir/plugstack.conf
MailProg=/bin/true
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SwitchType=switch/none
MpiDefault=none
JobCompType=jobcomp/none
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
DefMemPerCPU=$((real_mem / cpus))
SlurmdParameters=config_overrides
SchedulerType=sched/backfill
SchedulerParameters=batch_sched_delay=0,sched_interval=1,bf_interval=1
CompleteWait=0
EnforcePartLimits=ALL
ReturnToService=2
SlurmctldTimeout=30
SlurmdTimeout=30
MessageTimeout=10
InactiveLimit=0
KillWait=2
OverTimeLimit=0
MinJobAge=2
NodeName=$node NodeAddr=127.0.0.1 NodeHostname=$node CPUs=$cpus RealMemory=$real_mem State=UNKNOWN
PartitionName=debug Nodes=$node Default=YES MaxTime=INFINITE State=UP
EOF
}

do_start() {
  local i state
  if alive_pid munged "$munge_dir/munged.pid" >/dev/null &&
    alive_pid slurmctld "$run/slurmctld.pid" >/dev/null &&
    alive_pid slurmd "$run/slurmd.pid" >/dev/null; then
    echo "slurm cluster already running from $dir (node $node: $(node_state))"
    echo "export SLURM_CONF=$conf"
    return 0
  fi
  # Something half-running (or left over): start from a clean slate.
  do_stop
  ((${#socket} < 100)) || {
    echo "$0: DIR too long for a unix socket path: $socket" >&2
    exit 1
  }
  mkdir -p "$dir" "$munge_dir" "$run" "$logs" "$dir/state" "$dir/spool"
  chmod 0755 "$munge_dir" # clients need to reach the socket; the key itself is 0400
  if [[ ! -s $munge_dir/munge.key ]]; then
    rm -f "$munge_dir/munge.key"
    mungekey --create --keyfile="$munge_dir/munge.key" 2>/dev/null ||
      dd if=/dev/urandom of="$munge_dir/munge.key" bs=1024 count=1 status=none
  fi
  chmod 0400 "$munge_dir/munge.key"
  write_conf

  # The daemons fork into the background; their stdio goes to files so a caller's $(...) does not hang.
  if ! munged --force --socket="$socket" --key-file="$munge_dir/munge.key" --pid-file="$munge_dir/munged.pid" \
    --log-file="$munge_dir/munged.log" --seed-file="$munge_dir/munged.seed" \
    </dev/null >>"$logs/munged.out" 2>&1; then
    echo "$0: munged failed to start" >&2
    show_logs
    do_stop
    exit 1
  fi
  local failed=
  slurmctld -c -f "$conf" </dev/null >>"$logs/slurmctld.out" 2>&1 || failed="slurmctld exited with $?"
  [[ -n $failed ]] || slurmd -N "$node" -f "$conf" </dev/null >>"$logs/slurmd.out" 2>&1 || failed="slurmd exited with $?"

  state=
  for ((i = 0; i < 300; i++)); do # 30 s
    [[ -z $failed ]] || break
    state=$(node_state || true)
    [[ $state == idle ]] && break
    if ((i >= 20)); then # the daemons have written their pid files by now
      alive_pid munged "$munge_dir/munged.pid" >/dev/null || failed="munged died"
      alive_pid slurmctld "$run/slurmctld.pid" >/dev/null || failed="slurmctld died"
      alive_pid slurmd "$run/slurmd.pid" >/dev/null || failed="slurmd died"
    fi
    sleep 0.1
  done
  if [[ -n $failed || $state != idle ]]; then
    echo "$0: node $node not idle (state: '${state:-no answer}'${failed:+, $failed}) after $((i / 10)) s" >&2
    show_logs
    do_stop
    exit 1
  fi
  echo "slurm cluster aerotrack-test up from $dir (node $node, $(awk -F= '/^NodeName/ {print}' "$conf" | grep -o 'CPUs=[0-9]*'), ports $(grep -E '^Slurm(ctld|d)Port=' "$conf" | cut -d= -f2 | paste -sd/))"
  echo "export SLURM_CONF=$conf"
}

case $cmd in
  start) do_start ;;
  stop)
    do_stop
    echo "slurm cluster from $dir stopped"
    ;;
  *) usage ;;
esac
