#!/usr/bin/env bash
# The Slurm recipe of docs/batch.md (scripts/slurm-batch.sh) on a real one-node Slurm cluster:
# Debian's slurmctld and slurmd on this machine, with munge, configured here in a temporary
# folder (ports of their own, their own munge key and socket, state and spool in the folder).
#   1. The recipe as a 3-task array over tests/data/sweeps/three-subjects.yaml makes the same
#      dataset, byte for byte in every file, as a local `phantasm batch` of the sweep.
#   2. A second array whose task 2 is cancelled (scancel) while it makes its subject, then
#      submitted again, ends with that same dataset: the cancelled subject is made by the
#      resubmitted task 2, and tasks 1 and 3 make nothing again.
#   3. scripts/Snakefile in Snakemake's cluster mode (a job per subject, submitted with sbatch)
#      makes that same dataset.
# Every daemon and job is stopped at the end, whatever happens (trap). Before all that: the recipe
# docs/batch.md shows is the shipped one.
# Usage: slurm_cluster.sh PHANTASM SOURCE_DIR  (as root, like slurmd on a cluster)
set -euo pipefail

phantasm=$(realpath "${1:?usage: slurm_cluster.sh PHANTASM SOURCE_DIR}")
source_dir=$(realpath "${2:?usage: slurm_cluster.sh PHANTASM SOURCE_DIR}")
sweep=$source_dir/tests/data/sweeps/three-subjects.yaml
recipe=$source_dir/scripts/slurm-batch.sh

fail() {
  echo "FAIL: $*" >&2
  exit 1
}

for program in /usr/sbin/slurmctld /usr/sbin/slurmd /usr/sbin/munged /usr/bin/sbatch /usr/bin/squeue \
  /usr/bin/scancel /usr/bin/scontrol /usr/bin/sinfo /usr/bin/snakemake; do
  [ -x "$program" ] || fail "$program not found: run scripts/install-deps.sh (Debian's slurm-wlm, munge and snakemake)"
done
[ "$(id -u)" -eq 0 ] || fail "slurmd starts jobs as their user and runs as root: run this test as root"

# docs/batch.md shows the recipe as it is (its lines but the comments at the top).
documented=$(awk '/^### Slurm job array/ { section = 1 } section && /^```/ { if (code) exit; code = 1; next }
  code { print }' "$source_dir/docs/batch.md")
shipped=$(grep -v -e '^# ' -e '^#$' "$recipe")
[ "$documented" = "$shipped" ] || fail "docs/batch.md (Slurm job array) does not show $recipe as it is:
$(diff <(echo "$documented") <(echo "$shipped"))"

# Short path: munge's socket path must fit a sockaddr_un (108 bytes).
tmp=$(mktemp -d /tmp/phantasm-slurm.XXXXXX)
pids=()
holder= # the process group that holds a cache entry's lock in step 2

cleanup() {
  local status=$?
  set +e
  [ -n "$holder" ] && kill -- -"$holder" 2>/dev/null
  trap '' PIPE # a reader of this output that has gone away must not stop the cleanup
  if [ -e "$tmp/slurm.conf" ] && kill -0 "${pids[1]:-0}" 2>/dev/null; then
    # Every job of this cluster (it is ours alone); the node daemon kills their processes, so
    # it is given a moment before it is stopped too.
    SLURM_CONF=$tmp/slurm.conf timeout 10 /usr/bin/scancel --user="$(id -un)" 2>/dev/null
    for _ in $(seq 1 40); do
      [ -z "$(SLURM_CONF=$tmp/slurm.conf timeout 5 /usr/bin/squeue -h -o %i 2>/dev/null)" ] && break
      sleep 1
    done
  fi
  # Daemons in the reverse order of their start: slurmd, slurmctld, munged.
  for ((i = ${#pids[@]} - 1; i >= 0; i--)); do
    kill "${pids[i]}" 2>/dev/null
  done
  for pid in "${pids[@]}"; do
    for _ in $(seq 1 50); do
      kill -0 "$pid" 2>/dev/null || break
      sleep 0.2
    done
    kill -KILL "$pid" 2>/dev/null
    wait "$pid" 2>/dev/null
  done
  if [ "$status" -ne 0 ]; then
    for log in "$tmp"/log/*.log "$tmp"/jobs/*.log; do
      [ -f "$log" ] || continue
      echo "---- $(basename "$log") (last lines)" >&2
      tail -n 30 "$log" >&2
    done
  fi
  rm -rf "$tmp"
  exit "$status"
}
trap cleanup EXIT
trap 'exit 130' INT
trap 'exit 143' TERM

# The program as it is now, for every run of the test (a rebuild meanwhile would change the build
# id that the anatomy cache's keys hold).
cp "$phantasm" "$tmp/phantasm"
phantasm=$tmp/phantasm

# Polls `command...` five times a second until it succeeds; fails naming `what` after `seconds`.
wait_until() {
  local what=$1 seconds=$2
  shift 2
  for _ in $(seq 1 $((seconds * 5))); do
    if "$@"; then return 0; fi
    sleep 0.2
  done
  fail "timed out after $seconds s waiting for $what"
}

# Two free TCP ports on localhost (the kernel picks them).
free_ports() {
  /usr/bin/python3 - <<'EOF'
import socket
sockets = [socket.socket() for _ in range(2)]
for s in sockets:
    s.bind(("127.0.0.1", 0))
print(" ".join(str(s.getsockname()[1]) for s in sockets))
EOF
}

# munge: a key of our own and a socket in the folder (munged wants the folders on the socket's
# path searchable by everyone).
chmod 755 "$tmp"
mkdir -p "$tmp/munge" "$tmp/state" "$tmp/spool" "$tmp/log" "$tmp/jobs"
chmod 755 "$tmp/munge"
head -c 1024 /dev/urandom >"$tmp/munge/munge.key"
chmod 400 "$tmp/munge/munge.key"
/usr/sbin/munged --foreground --key-file="$tmp/munge/munge.key" --socket="$tmp/munge/socket" \
  --pid-file="$tmp/munge/munged.pid" --log-file="$tmp/log/munged.log" --seed-file="$tmp/munge/seed" \
  >>"$tmp/log/munged.log" 2>&1 &
pids+=($!)
wait_until "munged's socket" 30 test -S "$tmp/munge/socket"

# slurm.conf: the node as slurmd sees it (its CPUs, sockets, cores and threads), with memory
# enough for the recipe's --mem=4G whatever the machine has (config_overrides: the node is
# scheduled as configured).
read -r controller_port node_port < <(free_ports)
host=$(hostname -s)
node_hardware=$(/usr/sbin/slurmd -C | head -n 1 | sed -e 's/^NodeName=[^ ]* //' -e 's/ *RealMemory=[0-9]*//')
export SLURM_CONF=$tmp/slurm.conf
cat >"$SLURM_CONF" <<EOF
ClusterName=phantasm-test
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$controller_port
SlurmdPort=$node_port
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$tmp/munge/socket
StateSaveLocation=$tmp/state
SlurmdSpoolDir=$tmp/spool
SlurmctldPidFile=$tmp/slurmctld.pid
SlurmdPidFile=$tmp/slurmd.pid
SlurmctldLogFile=$tmp/log/slurmctld.log
SlurmdLogFile=$tmp/log/slurmd.log
MailProg=/bin/true
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
MpiDefault=none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
SlurmdParameters=config_overrides
ReturnToService=2
MinJobAge=3600
KillWait=30
NodeName=$host NodeAddr=127.0.0.1 $node_hardware RealMemory=8192 State=UNKNOWN
PartitionName=phantasm Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
/usr/sbin/slurmctld -D -f "$SLURM_CONF" >>"$tmp/log/slurmctld.log" 2>&1 &
pids+=($!)
/usr/sbin/slurmd -D -f "$SLURM_CONF" >>"$tmp/log/slurmd.log" 2>&1 &
pids+=($!)
node_idle() { [ "$(/usr/bin/sinfo -h -N -o %t 2>/dev/null)" = idle ]; }
wait_until "the node to be idle" 60 node_idle
echo "one-node cluster up: $host, controller port $controller_port, node port $node_port"

# The reference: a local batch of the sweep.
"$phantasm" batch "$sweep" -o "$tmp/local" --quiet || fail "local phantasm batch exited with $?"
[ "$(find "$tmp/local" -name provenance.json | wc -l)" -eq 3 ] || fail "the local batch did not make 3 subjects"

# Every file of folder $1 equals the local batch's, and no other file is there; the measured stage
# times (timing.json) and the reports that show them (sub-<id>.html, the dataset's index.html, which
# each shard writes) differ from run to run, and are only required to be there.
same_as_local() {
  diff -r -x timing.json -x 'sub-*.html' -x index.html "$tmp/local" "$1" >&2 || fail "$1 differs from the local batch (above)"
  for subject in 01 02 03; do
    [ -s "$1/derivatives/phantasm/sub-$subject.html" ] && [ -s "$1/derivatives/phantasm/sub-$subject/timing.json" ] ||
      fail "$1 lacks the report or the stage times of sub-$subject"
  done
  echo "$1: every file equals the local batch's ($(find "$1" -type f | wc -l) files)"
}

# Submits the recipe as a 3-task array writing into $1; prints the job id. $2... go to sbatch.
submit() {
  local out=$1
  shift
  PHANTASM=$phantasm /usr/bin/sbatch --parsable --array=1-3 --chdir="$tmp/jobs" "$@" "$recipe" "$sweep" "$out"
}
task_state() { /usr/bin/scontrol -o show job "${job}_$1" 2>/dev/null | grep -o 'JobState=[A-Z_]*' | cut -d= -f2; }
array_ended() { [ -z "$(/usr/bin/squeue -h -j "$job" -o %i 2>/dev/null)" ]; }
# Waits for the array $job to end and requires every task to have completed. (Polled five times
# a second: `sbatch --wait` polls at 2, 8 and then every 32 s, most of a short array's time.)
wait_for_array() {
  wait_until "job $job to end" 900 array_ended
  for task in 1 2 3; do
    [ "$(task_state "$task")" = COMPLETED ] || fail "task $task of job $job ended $(task_state "$task"), expected COMPLETED"
  done
}
# The local batch's anatomy cache (derivatives/phantasm/cache) copied into the dataset folder $1,
# so that its subjects read their anatomy, reference state and images instead of making them
# again: the folder must still end equal to the local batch's, cache included. The cancelled and
# resumed array (2.) starts cold: that a batch makes the same cache is checked there.
seed_cache() {
  mkdir -p "$1/derivatives/phantasm"
  cp -a "$tmp/local/derivatives/phantasm/cache" "$1/derivatives/phantasm/cache"
}

# 1. An array of three one-subject shards.
seed_cache "$tmp/cluster"
job=$(submit "$tmp/cluster") || fail "sbatch exited with $?"
wait_for_array
same_as_local "$tmp/cluster"

# 2. Task 2 cancelled while it makes sub-02, the array submitted again. A small head takes about
# a second, less than it takes to see the task start: sub-02 is held inside its subject by this
# test, which holds the lock of sub-02's anatomy cache entry (the entry the local batch named in
# its log; each subject's seed makes its own anatomy) until the task is cancelled. Tasks 1 and 3
# need other entries and run on.
out=$tmp/resumed
entry=$(sed -n 's/.*organ geometry kept in the anatomy cache as entry \([0-9a-f]*\).*/\1/p' \
  "$tmp/local/derivatives/phantasm/sub-02/log.txt")
[ -n "$entry" ] || fail "the local batch's sub-02 log names no anatomy cache entry"
lock_name=$(cd "$tmp/local/derivatives/phantasm/cache" && ls anatomy-"$entry"*.lock)
mkdir -p "$out/derivatives/phantasm/cache"
# In a session of its own (flock and its sleep share the lock): killed as a group, here or by
# the cleanup.
setsid /usr/bin/flock -x "$out/derivatives/phantasm/cache/$lock_name" sleep 900 </dev/null >/dev/null 2>&1 &
holder=$!
job=$(submit "$out")
task2_log=$tmp/jobs/phantasm-sweep-${job}_2.log
# Working: running, and its batch has started the subject (its first line says so).
task2_working() { [ "$(task_state 2)" = RUNNING ] && grep -q '1 to run' "$task2_log" 2>/dev/null; }
wait_until "task 2 of job $job to start its subject" 600 task2_working
sleep 1
[ ! -e "$out/derivatives/phantasm/sub-02/provenance.json" ] || fail "sub-02 was complete before task 2 was cancelled"
/usr/bin/scancel "${job}_2"
task2_cancelled() { [ "$(task_state 2)" = CANCELLED ]; }
wait_until "task 2 of job $job to be cancelled" 60 task2_cancelled
kill -- -"$holder" 2>/dev/null || true
wait "$holder" 2>/dev/null || true
holder=
wait_until "job $job to end" 900 array_ended
[ "$(task_state 2)" = CANCELLED ] || fail "task 2 ended $(task_state 2), expected CANCELLED"
for task in 1 3; do
  [ "$(task_state "$task")" = COMPLETED ] || fail "task $task ended $(task_state "$task"), expected COMPLETED"
done
[ ! -e "$out/derivatives/phantasm/sub-02/provenance.json" ] || fail "the cancelled task 2 completed sub-02"
echo "job $job: task 2 cancelled while making sub-02; tasks 1 and 3 completed"

job=$(submit "$out") || fail "sbatch exited with $?"
resubmitted=$job
wait_for_array
same_as_local "$out"
# Nothing lost and nothing made twice: task 2 made sub-02, tasks 1 and 3 found theirs complete.
grep -q '^\[batch\] 1 subjects made, 0 already complete, 0 failed' "$tmp/jobs/phantasm-sweep-${resubmitted}_2.log" ||
  fail "the resubmitted task 2 did not make sub-02"
for task in 1 3; do
  grep -q '^\[batch\] 0 subjects made, 1 already complete, 0 failed' \
    "$tmp/jobs/phantasm-sweep-${resubmitted}_${task}.log" || fail "the resubmitted task $task made its subject again"
done
echo "job $resubmitted: the resubmitted array made sub-02 only; the dataset equals the local batch"

# 3. Snakemake's cluster mode (docs/batch.md): one sbatch job per subject, submitted by Snakemake.
seed_cache "$tmp/snakemake-out"
/usr/bin/snakemake -s "$source_dir/scripts/Snakefile" --directory "$tmp/snakemake" --jobs 3 --latency-wait 30 \
  --rerun-incomplete --cluster "sbatch --cpus-per-task={threads} --mem=4G --output=phantasm-%j.log" \
  --config sweep="$sweep" out="$tmp/snakemake-out" threads=2 phantasm="$phantasm" >"$tmp/log/snakemake.log" 2>&1 ||
  fail "snakemake --cluster exited with $? ($tmp/log/snakemake.log: $(tail -n 20 "$tmp/log/snakemake.log"))"
[ "$(grep -c 'Submitted batch job' "$tmp/log/snakemake.log")" -eq 3 ] || fail "snakemake did not submit 3 Slurm jobs"
same_as_local "$tmp/snakemake-out"
