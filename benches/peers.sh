#!/usr/bin/env bash
# gpurt against POV-Ray on five SPD scenes at 512x512, one sample per pixel, both cores.
#
# Times each whole process (start-up, parsing, BVH, render, PNG writing) with
# /usr/bin/time, keeps the fastest of REPEAT runs (default 3; the machine may be shared),
# and prints a markdown table. gpurt renders with the CPU backend; when `gpurt --help`
# offers `--backend gpu`, a GPU run is timed too (failures are ignored: no adapter).
# POV-Ray reads the SPD generators' own POV-Ray versions of the scenes, with the command
# line of ../shared/peers/povray/README.md (-A: no antialiasing, +WT2: two threads).
#
# Usage: benches/peers.sh            (from anywhere; needs povray and ../shared)
#        REPEAT=5 benches/peers.sh
set -euo pipefail

ROOT=$(cd "$(dirname "$0")/.." && pwd)
SCENES_DIR="$ROOT/../shared/scenes/spd"
POV_DIR="$ROOT/../shared/peers/povray"
SCENES=(balls-4 gears-4 mount-7 teapot-6 tree-11)
SIZE=512
REPEAT=${REPEAT:-3}
TIME=/usr/bin/time

if [[ ! -x $TIME ]]; then
    echo "installing GNU time" >&2
    apt-get install -y time >/dev/null
fi
command -v povray >/dev/null || { echo "povray is not installed" >&2; exit 2; }
[[ -d $SCENES_DIR && -d $POV_DIR ]] || { echo "missing $SCENES_DIR or $POV_DIR" >&2; exit 2; }

(cd "$ROOT" && cargo build --release --quiet)
GPURT="$ROOT/target/release/gpurt"
HAVE_GPU=0
if "$GPURT" --help | grep -Eq -- '^\s+- gpu:'; then HAVE_GPU=1; fi

WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT

# Runs a command REPEAT times under /usr/bin/time; prints "best_wall peak_kb log_file" of
# the fastest run (the log holds the command's stderr, the time line last). Fails when the
# command fails.
timed() {
    local best="" best_kb="" best_log="" i log line wall kb
    for ((i = 0; i < REPEAT; i++)); do
        log=$(mktemp "$WORK/run.XXXXXX")
        "$TIME" -f "TIME %e %M" "$@" >/dev/null 2>"$log" || return 1
        line=$(grep '^TIME ' "$log" | tail -1)
        wall=$(awk '{print $2}' <<<"$line")
        kb=$(awk '{print $3}' <<<"$line")
        if [[ -z $best ]] || awk -v a="$wall" -v b="$best" 'BEGIN{exit !(a < b)}'; then
            best=$wall best_kb=$kb best_log=$log
        fi
    done
    echo "$best $best_kb $best_log"
}

mb() { awk -v k="$1" 'BEGIN{printf "%.0f", k / 1024}'; }

rows=()
adapter=""
for s in "${SCENES[@]}"; do
    echo "== $s" >&2
    out=$(timed "$GPURT" "$SCENES_DIR/$s.nff" -o "$WORK/$s-cpu.png" \
        --width $SIZE --height $SIZE --backend cpu --stats) || { echo "gpurt failed on $s" >&2; exit 1; }
    read -r g_wall g_kb g_log <<<"$out"
    g_mrays=$(grep -o '[0-9.]* Mrays/s' "$g_log" | awk '{print $1}')
    g_render=$(awk '$1 == "cpu" {print $2}' "$g_log")

    gpu_cell="-"
    if ((HAVE_GPU)); then
        if out=$(timed "$GPURT" "$SCENES_DIR/$s.nff" -o "$WORK/$s-gpu.png" \
            --width $SIZE --height $SIZE --backend gpu --stats -v); then
            read -r u_wall _ u_log <<<"$out"
            u_mrays=$(grep -o '[0-9.]* Mrays/s' "$u_log" | awk '{print $1}')
            adapter=$(grep -m1 '^adapter' "$u_log" | sed 's/^adapter *//') || true
            gpu_cell="$u_wall s ($u_mrays Mrays/s)"
        else
            gpu_cell="failed"
        fi
    fi

    gunzip -c "$POV_DIR/$s.pov.gz" >"$WORK/$s.pov"
    # POV-Ray resolves relative names against the current directory.
    out=$(cd "$WORK" && timed povray "+I$s.pov" "+O$s-pov.png" \
        +W$SIZE +H$SIZE -A +WT2 -D +FN) || { echo "povray failed on $s" >&2; exit 1; }
    read -r p_wall p_kb p_log <<<"$out"
    p_trace=$(grep 'Trace Time' "$p_log" | grep -o '([0-9.]* seconds)' | tr -d '(' | awk '{print $1}')

    ratio=$(awk -v p="$p_wall" -v g="$g_wall" 'BEGIN{printf "%.2f", p / g}')
    rows+=("| $s | $g_wall | $g_mrays | $(mb "$g_kb") | $p_wall | $(mb "$p_kb") | $ratio | $g_render / $p_trace | $gpu_cell |")
done

echo
echo "| scene | gpurt wall s | gpurt Mrays/s | gpurt peak MB | povray wall s | povray peak MB | povray / gpurt | render only s, gpurt / povray | gpurt --backend gpu |"
echo "|---|---:|---:|---:|---:|---:|---:|---:|---|"
printf '%s\n' "${rows[@]}"
echo
echo "${SIZE}x${SIZE}, 1 spp, $(nproc) threads; best of $REPEAT runs. Wall time and peak memory are"
echo "of the whole process; ratio = povray wall / gpurt wall. Render only: gpurt's 'cpu' time"
echo "(--stats) against POV-Ray's 'Trace Time' (its log), both without parsing and start-up."
if [[ -n $adapter ]]; then echo "GPU runs on: $adapter."; fi
