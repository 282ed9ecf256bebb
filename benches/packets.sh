#!/usr/bin/env bash
# How the CPU's packets scale: primary and shadow rays a second in packets
# (`examples/rays.rs`, PACKETS_ONLY=1) from 256x256 to 4096x4096 on one and on two
# threads, per scene. Prints a markdown table.
#
#   benches/packets.sh [SCENE...]    (default: teapot-6, gears-4 and balls-4)
#   SIZES="256 1024" THREADS_LIST="1 2" CLOCK=cpu benches/packets.sh
#
# With CLOCK=cpu the rates are of processor time (all threads together): on a machine
# shared with other work the thread scaling shows in wall-clock time only, so run it
# without CLOCK there, or read the 2-thread rate as per-processor-second.
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
SIZES=${SIZES:-256 512 1024 2048 4096}
THREADS_LIST=${THREADS_LIST:-1 2}
if [ $# -eq 0 ]; then
    set -- "$ROOT"/../shared/scenes/spd/{teapot-6,gears-4,balls-4}.nff
fi
(cd "$ROOT" && cargo build --release --quiet --example rays)
rate() { awk -v k="$2" '{for (i = 1; i < NF; i++) if ($i == k) {print $(i + 2); exit}}' <<<"$1"; }

header="| scene | threads |"
rule="|---|---:|"
for size in $SIZES; do
    header+=" ${size}² primary | ${size}² shadow |"
    rule+="---:|---:|"
done
echo "$header"
echo "$rule"
isa=""
for scene in "$@"; do
    name=$(basename "$scene" .nff)
    for threads in $THREADS_LIST; do
        row="| $name | $threads |"
        for size in $SIZES; do
            echo "== $name, $threads threads, $size" >&2
            out=$(PACKETS_ONLY=1 RAYON_NUM_THREADS=$threads "$ROOT/target/release/examples/rays" "$scene" "$size")
            isa=$(awk '{for (i = 1; i < NF; i++) if ($i == "isa") print $(i + 1)}' <<<"$out")
            row+=" $(rate "$out" primaryP) | $(rate "$out" shadowP) |"
        done
        echo "$row"
    done
done
echo
echo "Mrays/s in packets ($isa), best of five runs, ${CLOCK:-wall}-clock time; one primary ray a"
echo "pixel, its shadow rays to each point light."
