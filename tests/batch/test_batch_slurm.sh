#!/usr/bin/env bash
# tests/batch/test_batch_slurm.sh -- a batch on a real Slurm (docs/batch.md): starts munged,
# slurmctld and slurmd on this machine with a generated minimal slurm.conf (a temporary folder,
# free ports, no cgroups: proctrack/linuxproc, task/none), submits the documented job script
# examples/slurm/panelize-array.sbatch as a 3-task array over 12 generated garments (one broken
# on purpose) and the merge as a job depending on it, waits, checks every garment's folder, each
# shard's summary and the merged one, and stops the daemons. Every wait is bounded (a port taken
# meanwhile: other ports, up to three tries). Skips (exit 77, saying why) where
# Slurm or munge is not installed (scripts/install-deps.sh installs them), without root, or where
# the daemons do not start.
#
# SPDX-License-Identifier: GPL-3.0-or-later
set -u

HERE=$(cd "$(dirname "$0")" && pwd)
SOURCE_DIR=$(cd "$HERE/../.." && pwd)
source "$HERE/../cli/lib.sh"
source "$HERE/lib_garments.sh"

for tool in munged mungekey slurmctld slurmd sbatch squeue sinfo scontrol; do
    if ! command -v $tool >/dev/null 2>&1; then
        echo "SKIPPED: $tool not found (Debian's slurm-wlm and munge: scripts/install-deps.sh)"
        exit 77
    fi
done
if [ "$(id -u)" -ne 0 ]; then
    echo "SKIPPED: slurmd launches jobs as root only; run as root (CI does)"
    exit 77
fi

# ------------------------------------------------------------------ the daemons
S=$WORK/slurm
mkdir -p "$S/munge" "$S/state" "$S/spool"
chmod 700 "$S/munge"
stop_daemons() {
    [ -f "$S/slurm.conf" ] && SLURM_CONF=$S/slurm.conf timeout 10 scontrol shutdown >/dev/null 2>&1
    local pid_file pid
    for pid_file in "$S/slurmctld.pid" "$S/slurmd.pid" "$S/munge/munged.pid"; do
        [ -f "$pid_file" ] || continue
        pid=$(cat "$pid_file")
        for ((t = 0; t < 50; ++t)); do kill -0 "$pid" 2>/dev/null || break; kill "$pid" 2>/dev/null; sleep 0.1; done
        kill -KILL "$pid" 2>/dev/null
    done
}
trap 'stop_daemons; rm -rf "$WORK"' EXIT
skip_daemons() {
    echo "SKIPPED: $1"
    local log
    for log in "$S/munge/munged.log" "$S/slurmctld.log" "$S/slurmd.log"; do
        [ -f "$log" ] && { echo "--- $log"; tail -n 5 "$log"; }
    done
    exit 77
}

mungekey --create --keyfile="$S/munge/munge.key" >/dev/null 2>&1 ||
    dd if=/dev/urandom of="$S/munge/munge.key" bs=1024 count=1 status=none
chmod 600 "$S/munge/munge.key"
munged --force --key-file="$S/munge/munge.key" --socket="$S/munge/munge.sock" --pid-file="$S/munge/munged.pid" \
    --log-file="$S/munge/munged.log" --seed-file="$S/munge/munged.seed" >/dev/null 2>&1 ||
    skip_daemons "munged does not start here"

# Every Slurm client call is bounded: against a controller that is not there, one retries for minutes.
slurm() { timeout 10 "$@"; }
alive() { [ -f "$1" ] && kill -0 "$(cat "$1")" 2>/dev/null; }

# write_conf: slurm.conf with two ports below the ephemeral range (32768-60999), free right now.
write_conf() {
    local node ports
    ports=$(python3 -c '
import random, socket
ports = []
while len(ports) < 2:
    port = random.randrange(20000, 30000)
    s = socket.socket()
    try:
        s.bind(("", port))
        ports.append(port)
    except OSError:
        pass
    finally:
        s.close()
print(*ports)')
    node=$(hostname -s)
    cat >"$S/slurm.conf" <<EOF
ClusterName=pztest
SlurmctldHost=$node(127.0.0.1)
SlurmUser=root
SlurmdUser=root
SlurmctldPort=${ports% *}
SlurmdPort=${ports#* }
MessageTimeout=5
AuthType=auth/munge
AuthInfo=socket=$S/munge/munge.sock
CredType=cred/munge
StateSaveLocation=$S/state
SlurmdSpoolDir=$S/spool
SlurmctldPidFile=$S/slurmctld.pid
SlurmdPidFile=$S/slurmd.pid
SlurmctldLogFile=$S/slurmctld.log
SlurmdLogFile=$S/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
MpiDefault=none
SwitchType=switch/none
NodeName=$node NodeAddr=127.0.0.1 CPUs=$(nproc) State=UNKNOWN
PartitionName=pz Nodes=ALL Default=YES MaxTime=INFINITE State=UP
EOF
}

# start_slurm: slurmctld answering and the node idle within 30 s, else 1.
start_slurm() {
    local deadline=$((SECONDS + 30))
    slurmctld -f "$SLURM_CONF" >/dev/null 2>&1 || return 1
    until slurm scontrol ping 2>/dev/null | grep -q UP; do
        alive "$S/slurmctld.pid" && [ $SECONDS -lt $deadline ] || return 1
        sleep 0.2
    done
    slurmd -f "$SLURM_CONF" >/dev/null 2>&1 || return 1
    until [ "$(slurm sinfo -h -o %T 2>/dev/null)" = idle ]; do
        alive "$S/slurmctld.pid" && alive "$S/slurmd.pid" && [ $SECONDS -lt $deadline ] || return 1
        sleep 0.2
    done
}

export SLURM_CONF=$S/slurm.conf
started=0
for attempt in 1 2 3; do # a port taken between the choice and the bind: other ports, again
    write_conf
    if start_slurm; then
        started=1
        break
    fi
    slurm scontrol shutdown >/dev/null 2>&1
    for pid_file in "$S/slurmctld.pid" "$S/slurmd.pid"; do
        alive "$pid_file" && kill -KILL "$(cat "$pid_file")"
        rm -f "$pid_file"
    done
    rm -rf "$S/state" "$S/spool" && mkdir -p "$S/state" "$S/spool"
done
[ $started -eq 1 ] || skip_daemons "slurmctld and slurmd did not come up (3 tries of 30 s)"

# ------------------------------------------------------------------ the array and the merge
check "generate the garments" make_garments "$WORK/in" 11 broken
export PANELIZE=$BIN
array=$(slurm sbatch --parsable --array=0-2 --chdir="$WORK" --output="$WORK/task-%a.log" \
    "$SOURCE_DIR/examples/slurm/panelize-array.sbatch" "$WORK/in" "$WORK/res" --outputs json,svg)
check "sbatch the array: '$array'" [ -n "$array" ]
merge=$(slurm sbatch --parsable --dependency=afterany:"$array" --chdir="$WORK" --output="$WORK/merge.log" \
    --wrap "\"$BIN\" batch --merge \"$WORK/res\"")
check "sbatch the merge: '$merge'" [ -n "$merge" ]
deadline=$((SECONDS + 180))
until queue=$(slurm squeue -h 2>&1) && [ -z "$queue" ]; do # every job done: at most 3 minutes
    [ $SECONDS -lt $deadline ] || break
    sleep 0.2
done
check "every job ended within 3 minutes: $queue" [ -z "$queue" ]

names="broken g00 g01 g02 g03 g04 g05 g06 g07 g08 g09 g10"
rows() { python3 -c 'import json,sys; print(" ".join(json.loads(l)["name"] for l in open(sys.argv[1])))' "$1"; }
for i in 0 1 2; do
    check "task $i: its shard's summary" [ -f res/summary-$i-of-3.jsonl ]
    check "task $i: the log says it ran its shard: $(tail -n 3 task-$i.log 2>/dev/null)" grep -q '^garments: *4$' task-$i.log
done
check "task 0 took every third garment from 0" [ "$(rows res/summary-0-of-3.jsonl)" = "broken g02 g05 g08" ]
check "the merged summary lists every garment once, in order" [ "$(rows res/summary.jsonl 2>/dev/null)" = "$names" ]
check "the merged summary.csv: a header and 12 rows" [ "$(wc -l <res/summary.csv)" -eq 13 ]
check "the merge job's totals: $(cat merge.log)" grep -q '^failed: *1$' merge.log
check "the merge job names the failure" grep -q 'batch: 1 of 12 garments failed' merge.log
check "broken: failed, category data" [ "$(summary_field res/summary.jsonl broken status)/$(summary_field res/summary.jsonl broken category)" = failed/data ]
for g in ${names#broken }; do
    check "$g: ok in the merged summary" [ "$(summary_field res/summary.jsonl $g status)" = ok ]
    check "$g: its folder complete (report.json, pattern.svg, batch.json)" \
        [ -f res/$g/report.json -a -f res/$g/pattern.svg -a -f res/$g/batch.json ]
done
check "the pieces in the summary are report.json's" python3 - res <<'PY'
import json, sys
for line in open(sys.argv[1] + "/summary.jsonl"):
    row = json.loads(line)
    if row["status"] == "ok":
        report = json.load(open(f"{sys.argv[1]}/{row['name']}/report.json"))
        assert row["pieces"] == report["summary"]["panel_count"], row
PY

finish
