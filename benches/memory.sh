#!/usr/bin/env bash
# Peak memory of a whole command-line render on the CPU at one sample per pixel, at
# 8192x8192 and 16384x16384 (the largest image gpurt makes), of a small scene (one lit
# ball), against the goal of 16 bytes a pixel plus 100 MB (a film of linear floats is 12).
#
# Peak memory is the process's peak resident set (VmHWM, as `--stats` prints it), which
# includes the binary, thread stacks and allocator slack. With a second binary (one built
# before a change), both run on the same scene and sizes, one after the other.
#
# Usage: benches/memory.sh [BASE_BINARY]       (from anywhere)
#        SIZES="4096 8192" FORMATS="png exr" benches/memory.sh
#        NEW=target/debug/gpurt benches/memory.sh
set -euo pipefail

ROOT=$(cd "$(dirname "$0")/.." && pwd)
SIZES=${SIZES:-8192 16384}
FORMATS=${FORMATS:-png}
BASE=${1:-}
if [[ -z ${NEW:-} ]]; then
    (cd "$ROOT" && cargo build --release --quiet)
    NEW="$ROOT/target/release/gpurt"
fi

WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
cat >"$WORK/ball.nff" <<'EOF'
b 0.1 0.2 0.3
v
from 0 -4 1
at 0 0 0
up 0 0 1
angle 40
resolution 64 64
l 2 -3 4
f 1 0.5 0.2 0.8 0 1 0 1
s 0 0 0 1
EOF

# Peak resident MiB of one render: binary, side, format.
peak_mib() {
    local out="$WORK/out.$3"
    "$1" "$WORK/ball.nff" --width "$2" --height "$2" --spp 1 --backend cpu --stats \
        -o "$out" 2>&1 | awk '/^peak memory/ {print $3}'
    rm -f "$out"
}

echo "CPU render of one lit ball, 1 spp; peak resident memory"
if [[ -n $BASE ]]; then
    echo "| size | format | before MiB | before B/px | MiB | B/px | goal MiB (16 B/px + 100 MB) |"
    echo "|---|---|---:|---:|---:|---:|---:|"
else
    echo "| size | format | MiB | B/px | goal MiB (16 B/px + 100 MB) |"
    echo "|---|---|---:|---:|---:|"
fi
for side in $SIZES; do
    pixels=$((side * side))
    goal=$(awk -v p="$pixels" 'BEGIN {printf "%.0f", (16 * p + 100e6) / 1048576}')
    for format in $FORMATS; do
        new=$(peak_mib "$NEW" "$side" "$format")
        bpp=$(awk -v m="$new" -v p="$pixels" 'BEGIN {printf "%.2f", m * 1048576 / p}')
        if [[ -n $BASE ]]; then
            old=$(peak_mib "$BASE" "$side" "$format")
            obpp=$(awk -v m="$old" -v p="$pixels" 'BEGIN {printf "%.2f", m * 1048576 / p}')
            echo "| ${side}x$side | $format | $old | $obpp | $new | $bpp | $goal |"
        else
            echo "| ${side}x$side | $format | $new | $bpp | $goal |"
        fi
    done
done
