#!/usr/bin/env bash
# Animated scenes (AFF) rendered as sequences, side by side in one run: for each scene,
# backend and size, the frames a second of the whole sequence and, per frame on average,
# the time placing the moving parts and building the tree took against the time tracing
# took (`--stats`), for each way of making the frames' trees (`GPURT_FRAME_TREE`): the
# whole scene's built anew (`whole`), the still part's kept and the moving part's built
# anew (`rebuild`) or refitted (`refit`), or refitted until worn (`auto`, the default).
# How build time grows with the moving geometry's size is the point of the generated
# scenes: an SPD mountain of 2 to 131 thousand triangles (mount-5, 7 and 8) turning
# about z, all of it moving.
# BART's own scenes are rendered too (with --lenient, which its robots need) where
# BART=DIR names a copy of them (DIR holding scene_kitchen/aff/kitchen.aff and
# scene_robot/aff/Robot.aff).
#
# Usage: benches/animation.sh
#        FRAMES=8 SIZES="512x512 1920x1080" BACKENDS="cpu gpu" TREES="whole auto" \
#            BART=~/bart benches/animation.sh
#        (the GPU backend is whatever adapter `--backend gpu` finds: lavapipe on a machine
#        without a GPU; NO_GPU=1 leaves it out)
set -euo pipefail

ROOT=$(cd "$(dirname "$0")/.." && pwd)
SPD="$ROOT/../shared/scenes/spd"
FRAMES=${FRAMES:-8}
SIZES=${SIZES:-"512x512 1920x1080"}
BACKENDS=${BACKENDS:-"cpu gpu"}
TREES=${TREES:-"whole rebuild refit auto"}
[[ -n ${NO_GPU:-} ]] && BACKENDS=cpu
(cd "$ROOT" && cargo build --release --quiet)
GPURT="$ROOT/target/release/gpurt"
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT

# An AFF scene in which all of `$1` (an NFF file, its own view and lights included)
# turns about z by 10 degrees a time unit, over FRAMES frames from t = 0 to 1.
spinning() {
    cat <<EOF
a 0 1 $FRAMES
x spin {
  i 0 $1
}
k spin {
  rot 4
  -1  0 0 1 -10  0 0 0
   0  0 0 1   0  0 0 0
   1  0 0 1  10  0 0 0
   2  0 0 1  20  0 0 0
}
EOF
}

scenes=("$ROOT/scenes/orbit.aff")
for m in mount-5 mount-7 mount-8; do
    f=$(ls "$SPD/$m".nff* 2>/dev/null | head -1) || true
    if [[ -n $f ]]; then
        spinning "$f" >"$OUT/$m-spin.aff"
        scenes+=("$OUT/$m-spin.aff")
    fi
done
if [[ -n ${BART:-} ]]; then
    for s in scene_kitchen/aff/kitchen.aff scene_robot/aff/Robot.aff; do
        [[ -f $BART/$s ]] && scenes+=("$BART/$s")
    done
fi

# The still and the moving primitives of a scene (`gpurt info --json`).
counts() {
    "$GPURT" info "$1" --json --lenient 2>/dev/null | python3 -c '
import json, sys
v = json.load(sys.stdin)
m = (v["animation"] or {}).get("moving", {})
still = v["spheres"] + v["triangles"] + v["cones"] + v["boxes"]
print(still, sum(m.values()))'
}
# Fields of the `--stats` lines of a sequence.
field() { awk -v k="$2" -v n="$3" '$1 == k {print $n; exit}' <<<"$1"; }

echo "| scene | still prims | moving prims | backend | size | trees | frames | frames/s | build ms/frame | trace ms/frame | write ms/frame | trees made |"
echo "|---|---:|---:|---|---|---|---:|---:|---:|---:|---:|---|"
for scene in "${scenes[@]}"; do
    name=$(basename "$scene" .aff)
    read -r still moving < <(counts "$scene")
    for backend in $BACKENDS; do
        for size in $SIZES; do
            for tree in $TREES; do
                w=${size%x*}
                h=${size#*x}
                echo "== $name $backend $size $tree" >&2
                rm -rf "$OUT/frames"
                s=$(GPURT_FRAME_TREE=$tree "$GPURT" "$scene" --frames "0..$((FRAMES - 1))" \
                    -o "$OUT/frames/f-%04d.png" --width "$w" --height "$h" \
                    --backend "$backend" --lenient --stats 2>&1 | grep -v "warning:") || {
                    echo "| $name | $still | $moving | $backend | $size | $tree | failed ||||||"
                    continue
                }
                # `frame       0.0009 s place + build, 0.0214 s trace, 0.0039 s write (mean of 48)`
                ms() { awk -v x="$1" 'BEGIN {printf "%.1f", x * 1000}'; }
                made=$(awk '$1 == "trees" {$1 = ""; sub(/^ +/, ""); print; exit}' <<<"$s")
                echo "| $name | $still | $moving | $backend | $size | $tree | $(field "$s" sequence 2) | $(field "$s" sequence 7 | tr -d '(') | $(ms "$(field "$s" frame 2)") | $(ms "$(field "$s" frame 7)") | $(ms "$(field "$s" frame 10)") | $made |"
            done
        done
    done
done
echo
