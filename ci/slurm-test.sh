#!/usr/bin/env bash
# The farm for real: starts a single-node Slurm cluster on this machine
# (munged, slurmctld, slurmd in the background, no systemd, a generated
# slurm.conf naming this host), renders a small scene in 8 tiles through
# farm/slurm/submit.sh, and checks that the assembled frame equals a
# one-process render bit for bit (idiff, every channel). Then the failure
# path: one task of the array cancelled, `assemble` must refuse naming the
# missing pixels, a re-submission must render only that tile, and the frame
# then assembles. Every daemon it started is stopped on exit, failure or not.
#
#   ci/slurm-test.sh [path/to/lightcuts]    (default: target/release/lightcuts)
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
lightcuts=$(realpath "${1:-$repo/target/release/lightcuts}")
"$repo/ci/setup.sh" --slurm

work=$(mktemp -d /tmp/lightcuts-slurm.XXXXXX)
chmod 755 "$work"
pids=()
cleanup() {
    local status=$?
    for pid in "${pids[@]}"; do kill "$pid" 2>/dev/null || true; done
    for pid in "${pids[@]}"; do
        for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
        kill -9 "$pid" 2>/dev/null || true
    done
    if [ $status -ne 0 ]; then
        echo "ci/slurm-test.sh: FAILED; logs:" >&2
        tail -n 20 "$work"/*.log "$work"/*.out "$work"/out*/logs/*.log 2>/dev/null >&2 || true
    fi
    rm -rf "$work"
    exit $status
}
trap cleanup EXIT INT TERM

host=$(hostname -s)
cpus=$(nproc)
# Free ports, so that a real cluster on this machine is never disturbed.
port() { python3 -c 'import socket; s = socket.socket(); s.bind(("", 0)); print(s.getsockname()[1])'; }
ctld_port=$(port)
slurmd_port=$(port)

mkdir -p "$work/munge" "$work/state" "$work/spool"
chmod 700 "$work/munge"
mungekey --create --keyfile "$work/munge/munge.key" --force
chmod 600 "$work/munge/munge.key"
munged --key-file="$work/munge/munge.key" --socket="$work/munge/munge.socket" \
    --pid-file="$work/munge/munged.pid" --log-file="$work/munged.log" \
    --seed-file="$work/munge/munge.seed" --foreground --force >"$work/munged.out" 2>&1 &
pids+=($!)

cat >"$work/slurm.conf" <<CONF
ClusterName=lightcutsci
SlurmctldHost=$host
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$work/munge/munge.socket
CredType=cred/munge
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/slurmctld.log
SlurmdLogFile=$work/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/backfill
ReturnToService=2
MpiDefault=none
NodeName=$host CPUs=$cpus RealMemory=1024 State=UNKNOWN
PartitionName=ci Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF="$work/slurm.conf"
for _ in $(seq 50); do [ -S "$work/munge/munge.socket" ] && break; sleep 0.1; done
slurmctld -D -f "$SLURM_CONF" -i >"$work/slurmctld.out" 2>&1 &
pids+=($!)
slurmd -D -f "$SLURM_CONF" -N "$host" >"$work/slurmd.out" 2>&1 &
pids+=($!)
for _ in $(seq 120); do
    state=$(sinfo -h -n "$host" -o %T 2>/dev/null || true)
    [ "$state" = idle ] && break
    sleep 0.5
done
[ "$state" = idle ] || { echo "the node never became idle (state '$state')" >&2; exit 1; }
echo "ci/slurm-test.sh: Slurm $(sinfo --version | cut -d' ' -f2) up on $host ($cpus CPUs)" >&2

scene="$repo/scenes/cornell.toml"
args=(--resolution 64x48 --spp 2 --quiet)
"$lightcuts" render "$scene" "${args[@]}" -o "$work/one-process.exr" >/dev/null

# Waits until the jobs given have left the queue.
wait_for() {
    for _ in $(seq 600); do
        [ -z "$(squeue -h -j "$(IFS=,; echo "$*")" 2>/dev/null)" ] && return 0
        sleep 0.5
    done
    echo "jobs $* still queued after 300 s" >&2
    squeue >&2
    return 1
}

# 1. The whole frame in 8 tiles.
read -r array assemble < <(LIGHTCUTS="$lightcuts" "$repo/farm/slurm/submit.sh" "$scene" "$work/out" 8 "${args[@]}")
wait_for "$array" "$assemble"
idiff -q -fail 0 -failpercent 0 -warn 0 "$work/out/frame.exr" "$work/one-process.exr" >&2
echo "ci/slurm-test.sh: 8 tiles on Slurm assemble to the one-process render, bit for bit" >&2

# 2. One task cancelled: the array held, task 3 cancelled, then released.
array=$(LIGHTCUTS="$lightcuts" SCENE="$(realpath "$scene")" OUT_DIR="$work/out2" TILES=8 RENDER_ARGS="${args[*]}" \
    bash -c 'mkdir -p "$OUT_DIR/logs" && sbatch --parsable --hold --array=0-7 --export=ALL \
        --output="$OUT_DIR/logs/tile-%a.log" '"$repo"'/farm/slurm/render-tile.sbatch')
array=${array%%;*}
scancel "${array}_3"
scontrol release "$array"
wait_for "$array"
tiles=()
for i in $(seq 0 7); do tiles+=("$work/out2/tile-$i.exr"); done
if message=$("$lightcuts" assemble "$work/out2/frame.exr" "${tiles[@]}" 2>&1); then
    echo "assemble accepted a frame with a missing tile" >&2
    exit 1
fi
echo "$message" | grep -q "are in no tile: x 0..64, y 18..24" ||
    { echo "unexpected refusal: $message" >&2; exit 1; }
[ ! -e "$work/out2/frame.exr" ]
echo "ci/slurm-test.sh: with task 3 cancelled, assemble refuses: $message" >&2

# 3. The same submission again renders only tile 3, then assembles.
read -r array assemble < <(LIGHTCUTS="$lightcuts" "$repo/farm/slurm/submit.sh" "$scene" "$work/out2" 8 "${args[@]}")
wait_for "$array" "$assemble"
skipped=$(grep -l "exists, skipped" "$work"/out2/logs/tile-*.log | wc -l)
rendered=$(grep -l "output .*tile-3.exr" "$work"/out2/logs/tile-*.log | wc -l)
[ "$skipped" -eq 7 ] && [ "$rendered" -eq 1 ] ||
    { echo "re-submission: $skipped tiles skipped, $rendered rendered (want 7 and 1)" >&2; exit 1; }
idiff -q -fail 0 -failpercent 0 -warn 0 "$work/out2/frame.exr" "$work/one-process.exr" >&2
echo "ci/slurm-test.sh: re-submitted, only tile 3 rendered; the frame assembles bit for bit" >&2
