#!/usr/bin/env bash
# gpurt's CPU traversal against Embree 3 on the same rays: primary rays of a 512x512
# render and the shadow rays from their hits to each point light, on the same threads.
# `examples/rays.rs` traces them with our `closest_hit` and `transmission` and writes them
# out; `benches/embree/rays.c` traces the same file with Embree and says how often the
# answers match. Prints a markdown table.
#
#   benches/embree.sh [SCENE...]      (default: the five SPD scenes of benches/peers.sh)
#   THREADS=4 SIZE=1024 benches/embree.sh
#   GPURT_CPU_WALK=binary benches/embree.sh   (our side walks the binary tree, as the GPU)
#   SPP=16 benches/embree.sh   (our side traces the tree gpurt builds for a 16-sample render;
#                               the rays are the same)
#
# Needs Debian's libembree-dev (skipped with a message when it is missing) and ../shared.
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
THREADS=${THREADS:-2}
SIZE=${SIZE:-512}
if [[ ! -f /usr/include/embree3/rtcore.h ]]; then
    echo "skipped: Embree 3 is not installed (apt-get install -y libembree-dev)" >&2
    exit 0
fi
if [ $# -eq 0 ]; then
    set -- "$ROOT"/../shared/scenes/spd/{balls-4,gears-4,mount-7,teapot-6,tree-11}.nff
fi
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
cc -O3 -march=native -o "$WORK/rays" "$ROOT/benches/embree/rays.c" -lembree3 -lpthread -lm
(cd "$ROOT" && cargo build --release --quiet --example rays)

echo "| scene | primary rays | gpurt Mrays/s | Embree Mrays/s | gpurt / Embree | shadow rays | gpurt Mrays/s | Embree Mrays/s | gpurt / Embree | answers that agree (primary, shadow) |"
echo "|---|---:|---:|---:|---:|---:|---:|---:|---:|---|"
for scene in "$@"; do
    name=$(basename "$scene" .nff)
    ours=$(RAYON_NUM_THREADS=$THREADS "$ROOT/target/release/examples/rays" "$scene" "$SIZE" "$WORK/$name.rays")
    theirs=$("$WORK/rays" "$WORK/$name.rays" "$THREADS")
    field() { awk -v k="$2" '{for (i = 1; i < NF; i++) if ($i == k) {print $(i + 1); exit}}' <<<"$1"; }
    rate() { awk -v k="$2" '{for (i = 1; i < NF; i++) if ($i == k) {print $(i + 3); exit}}' <<<"$1"; }
    gp=$(rate "$ours" primary) gs=$(rate "$ours" shadow)
    ep=$(rate "$theirs" primary) es=$(rate "$theirs" shadow)
    agree=$(grep '^agree' <<<"$theirs" | awk '{print $3 ", " $11}')
    ratio() { awk -v a="$1" -v b="$2" 'BEGIN{printf "%.2f", a / b}'; }
    echo "| $name | $(field "$ours" primary) | $gp | $ep | $(ratio "$gp" "$ep") | $(field "$ours" shadow) | $gs | $es | $(ratio "$gs" "$es") | $agree |"
done
echo
echo "${SIZE}x${SIZE}, one primary ray per pixel, $THREADS threads on both sides, chunks of 64 rays;"
echo "best of five runs. Embree: rtcIntersect1 / rtcOccluded1, spheres as SPHERE_POINT,"
echo "cones as user geometry (our intersection in C). gpurt: closest_hit / transmission."
