#!/usr/bin/env bash
# Checks submit.sh on a real single-node Slurm started here (Debian's slurm-wlm and munge,
# as root, no systemd): renders a bundled scene as 4 shards on a job array, merges them in
# a job that depends on the array, and compares the result with a single-process render,
# byte for byte; then renders an animated scene's 48 frames on a 4-task array and compares
# them with the frames one process writes. Stops the daemons it started. Not run by CI.
#
#   deploy/slurm/local-test.sh          (needs a release build: cargo build --release)
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
GPURT="$ROOT/target/release/gpurt"
[ -x "$GPURT" ] || { echo "build first: cargo build --release" >&2; exit 2; }
command -v slurmctld >/dev/null || apt-get install -y -qq slurm-wlm munge >/dev/null
WORK=$(mktemp -d /tmp/gpurt-slurm.XXXXXX)
HOST=$(hostname -s)
cleanup() {
    for pid in "$WORK"/slurmd.pid "$WORK"/slurmctld.pid; do
        [ -f "$pid" ] && kill "$(cat "$pid")" 2>/dev/null || true
    done
}
trap cleanup EXIT

# munge: a key, its run directory, the daemon as its own user.
[ -f /etc/munge/munge.key ] || mungekey -c
chown munge:munge /etc/munge/munge.key && chmod 0400 /etc/munge/munge.key
mkdir -p /run/munge && chown munge:munge /run/munge
pgrep -x munged >/dev/null || su -s /bin/sh munge -c /usr/sbin/munged
munge -n | unmunge >/dev/null

MEM=$(awk '/MemTotal/ {printf "%d", $2 / 1024 * 0.8}' /proc/meminfo)
mkdir -p "$WORK/state" "$WORK/spool" /etc/slurm
cat > /etc/slurm/slurm.conf <<CONF
ClusterName=gpurt-local
SlurmctldHost=$HOST
AuthType=auth/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
JobAcctGatherType=jobacct_gather/none
ReturnToService=2
SlurmUser=root
StateSaveLocation=$WORK/state
SlurmdSpoolDir=$WORK/spool
SlurmctldPidFile=$WORK/slurmctld.pid
SlurmdPidFile=$WORK/slurmd.pid
SlurmctldLogFile=$WORK/slurmctld.log
SlurmdLogFile=$WORK/slurmd.log
NodeName=$HOST CPUs=$(nproc) RealMemory=$MEM State=UNKNOWN
PartitionName=main Nodes=$HOST Default=YES MaxTime=INFINITE State=UP
CONF
slurmctld
slurmd
for _ in $(seq 30); do sinfo -h -o %T 2>/dev/null | grep -q idle && break; sleep 1; done
sinfo

# Waits until no job is queued, at most 2 minutes.
wait_for_queue() {
    for _ in $(seq 120); do
        [ -z "$(squeue -h)" ] && return
        sleep 1
    done
    echo "jobs still queued after 2 minutes" >&2
    squeue
    exit 1
}

cd "$WORK"
SCENE="$ROOT/scenes/glass.nff"
OPTS=(--width 160 --height 120 --spp 4 --backend cpu)
merge_job=$(GPURT="$GPURT" "$ROOT/deploy/slurm/submit.sh" "$SCENE" "$WORK/merged.png" 4 "${OPTS[@]}")
echo "merge job $merge_job submitted after a 4-task array"
wait_for_queue
ls "$WORK/merged.shards"
"$GPURT" "$SCENE" "${OPTS[@]}" -o "$WORK/single.png"
if cmp "$WORK/merged.png" "$WORK/single.png"; then
    echo "OK: the array's merged image is the single-process render, byte for byte"
else
    echo "FAILED: the merged image differs" >&2
    exit 1
fi

# An animated scene's frames shared out by an array job: 4 tasks, each every 4th of the
# 48 frames of scenes/orbit.aff (I from SLURM_ARRAY_TASK_ID), against the frames one
# process writes.
ANIM="$ROOT/scenes/orbit.aff"
FOPTS=(--width 80 --height 60 --backend cpu)
sbatch --array=0-3 --wrap "'$GPURT' '$ANIM' --frames all --shard /4 --resume ${FOPTS[*]} -o '$WORK/frames/f-%04d.png'" >/dev/null
echo "a 4-task array over the 48 frames of orbit.aff submitted"
wait_for_queue
"$GPURT" "$ANIM" --frames all "${FOPTS[@]}" -o "$WORK/single-frames/f-%04d.png"
if [ "$(ls "$WORK/frames" | wc -l)" = 48 ] && diff -r "$WORK/frames" "$WORK/single-frames"; then
    echo "OK: the array's 48 frames are the single-process sequence, byte for byte"
else
    echo "FAILED: the array's frames differ" >&2
    exit 1
fi

