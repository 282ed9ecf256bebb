#!/usr/bin/env bash
# The viewer's speed in a real window (Xvfb): for each scene and display mode, the time
# from launch to the first frame and to the first ray-traced image, frames per second and
# the time to draw one, and samples per second at 800x600.
#
#   benches/viewer.sh [SCENE...]     (default: balls-4, mount-7 and teapot-6 of ../shared)
#   BACKEND=gpu benches/viewer.sh    (the tracer: auto, the default, gpu or cpu)
#
# Each run is `gpurt view --stats` driven by a script:
#   still      ray traced, no input: converges to --spp samples, then exits
#   overlay    the same with the wireframe over the image
#   moving     ray traced while the camera orbits a step every frame for 120 frames,
#              then quits: the wireframe stands in until a view has samples
#   wireframe  the wireframe alone, 300 frames
# Needs xvfb-run (apt-get install xvfb xauth) and a release build.
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${GPURT:-target/release/gpurt}
SPP=${SPP:-16}
SIZE=(--width 800 --height 600 --backend "${BACKEND:-auto}")
SHARED=../shared/scenes/spd
if [ $# -eq 0 ]; then
    set -- "$SHARED/balls-4.nff" "$SHARED/mount-7.nff" "$SHARED/teapot-6.nff"
fi
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
: > "$WORK/still.txt"
printf 'key m\nkey m\n' > "$WORK/overlay.txt"
{ for _ in $(seq 120); do printf 'drag 3 0\nwait 1\n'; done; echo 'key escape'; } > "$WORK/moving.txt"
printf 'key m\nwait 300\n' > "$WORK/wireframe.txt"

stat() { grep "^$1" "$2" | head -1 | sed "s/^$1 *//" || true; }
echo "| scene | mode | first frame | first image | frames/s | draw (median) | samples | rates |"
echo "|---|---|---|---|---|---|---|---|"
for scene in "$@"; do
    name=$(basename "$scene" .nff)
    # One run first to fill Mesa's shader cache, as any second launch finds it (the
    # pipeline depends on the samples per pixel: one, or more).
    xvfb-run -a "$BIN" view "$scene" "${SIZE[@]}" --spp "$SPP" --script "$WORK/still.txt" \
        --screenshot "$WORK/warm.png" >/dev/null 2>&1
    for mode in still overlay moving wireframe; do
        spp=(--spp "$SPP")
        xvfb-run -a "$BIN" view "$scene" "${SIZE[@]}" "${spp[@]}" --stats \
            --script "$WORK/$mode.txt" --screenshot "$WORK/$mode.png" >/dev/null 2>"$WORK/err"
        frames=$(stat frames "$WORK/err")
        fps=$(echo "$frames" | sed -n 's/.* shown, \([0-9.]*\) per second.*/\1/p')
        draw=$(echo "$frames" | sed -n 's/.*takes \([0-9.]* ms\).*/\1/p')
        view=$(stat "last view" "$WORK/err")
        echo "| $name | $mode | $(stat "first frame" "$WORK/err" | sed 's/ after launch//') \
| $(stat "first image" "$WORK/err" | sed 's/ after launch//') | ${fps:--} | ${draw:--} \
| $(echo "$view" | sed 's/:.*//') | $(echo "$view" | sed 's/^[^:]*: //') |"
    done
done
