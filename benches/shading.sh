#!/usr/bin/env bash
# What the shading model costs: `gpurt bench` CPU and GPU frame times under Phong and
# Blinn-Phong, and Phong against another gpurt binary (one built before --shading
# existed), the runs interleaved and the median of REPEAT kept per cell, so that a shared
# machine's drift falls on all columns alike.
#
# Usage: benches/shading.sh [BASE_BINARY]   (from anywhere; needs ../shared/scenes)
#        REPEAT=5 SIZE=256x256 BACKEND=gpu benches/shading.sh old/gpurt
#        NEW=target/debug/gpurt benches/shading.sh old-debug/gpurt   (same profile as BASE)
set -euo pipefail

ROOT=$(cd "$(dirname "$0")/.." && pwd)
SCENES_DIR="$ROOT/../shared/scenes/spd"
SCENES=(${SCENES:-balls-4 teapot-6 mount-7})
SIZE=${SIZE:-384x384}
REPEAT=${REPEAT:-5}
BACKEND=${BACKEND:-cpu}
BASE=${1:-}

if [[ -z ${NEW:-} ]]; then
    (cd "$ROOT" && cargo build --release --quiet)
    NEW="$ROOT/target/release/gpurt"
fi

# The frame time (ms) of one bench row: the GPU column, or the CPU one.
frame_ms() { # binary, scene, extra args...
    local bin=$1 scene=$2
    shift 2
    local row
    row=$("$bin" bench "$SCENES_DIR/$scene.nff" --sizes "$SIZE" --frames 3 \
        --backend "$BACKEND" "$@" 2>/dev/null | grep "^| $scene ")
    if [[ $BACKEND == cpu ]]; then
        awk -F'|' '{gsub(/ /, "", $16); print $16}' <<<"$row"
    else
        awk -F'|' '{gsub(/ /, "", $7); print $7}' <<<"$row"
    fi
}

median() { sort -g | awk '{a[NR] = $1} END {print a[int((NR + 1) / 2)]}'; }

echo "$BACKEND frame ms at $SIZE, 1 spp, median of $REPEAT interleaved runs"
if [[ -n $BASE ]]; then
    echo "| scene | before --shading | phong | blinn-phong |"
    echo "|---|---:|---:|---:|"
else
    echo "| scene | phong | blinn-phong |"
    echo "|---|---:|---:|"
fi
for s in "${SCENES[@]}"; do
    base=() phong=() blinn=()
    for ((i = 0; i < REPEAT; i++)); do
        [[ -n $BASE ]] && base+=("$(frame_ms "$BASE" "$s")")
        phong+=("$(frame_ms "$NEW" "$s" --shading phong)")
        blinn+=("$(frame_ms "$NEW" "$s" --shading blinn-phong)")
    done
    p=$(printf '%s\n' "${phong[@]}" | median)
    b=$(printf '%s\n' "${blinn[@]}" | median)
    if [[ -n $BASE ]]; then
        o=$(printf '%s\n' "${base[@]}" | median)
        echo "| $s | $o | $p | $b |"
    else
        echo "| $s | $p | $b |"
    fi
done
