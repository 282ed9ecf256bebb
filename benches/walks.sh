#!/usr/bin/env bash
# The GPU's ways of tracing, side by side in one run: `gpurt bench` on each scene under
# each setting, the settings interleaved scene by scene and round by round (the machine
# may be shared: only figures from one run compare), then one markdown table with a
# column naming the setting. A setting is a list of environment assignments, e.g.
# `GPURT_TRAVERSAL=wide` or `GPURT_TRAVERSAL=cwide` or `GPURT_KERNELS=wavefront`, where
# `BIN=path` runs another build (before and after a change); each row has the GPU's Mrays/s by
# kind of ray and the BVH nodes (and node bytes) a ray of each kind fetched.
#
# Defaults: the issue's lavapipe figures (balls-4, gears-4, teapot-6, and two
# glass and mirror scenes of our own, 512x512, 4 spp, depth 5), the four-wide walk
# against the compressed eight-wide one, two rounds.
#
# Usage: benches/walks.sh [SETTING...]
#        SCENES="a.nff b.nff" SIZE=1920x1080 SPP=1 DEPTH=5 ROUNDS=3 FRAMES=3 benches/walks.sh \
#            GPURT_TRAVERSAL=wide GPURT_TRAVERSAL=cwide
#        BIN=path/to/gpurt (default: builds and uses target/debug/gpurt; its profile
#        optimises our code, opt-level 2)
set -euo pipefail

ROOT=$(cd "$(dirname "$0")/.." && pwd)
SPD="$ROOT/../shared/scenes/spd"
SCENES=${SCENES:-"$SPD/balls-4.nff $SPD/gears-4.nff $SPD/teapot-6.nff $ROOT/scenes/glass.nff $ROOT/scenes/mirrors.nff"}
SIZE=${SIZE:-512x512}
SPP=${SPP:-4}
DEPTH=${DEPTH:-5}
ROUNDS=${ROUNDS:-2}
FRAMES=${FRAMES:-1}
if [[ $# -eq 0 ]]; then
    set -- GPURT_TRAVERSAL=wide GPURT_TRAVERSAL=cwide
fi
if [[ -z ${BIN:-} ]]; then
    (cd "$ROOT" && cargo build --quiet)
    BIN="$ROOT/target/debug/gpurt"
fi
export MESA_SHADER_CACHE_DIR=${MESA_SHADER_CACHE_DIR:-$ROOT/target/mesa-shader-cache}
export GPURT_CACHE_DIR=${GPURT_CACHE_DIR:-$ROOT/target/gpurt-cache}

rows=$(mktemp)
trap 'rm -f "$rows"' EXIT
header=""
echo "machine: $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg); $SIZE, $SPP spp, depth $DEPTH, $ROUNDS rounds" >&2
for round in $(seq 1 "$ROUNDS"); do
    for scene in $SCENES; do
        for setting in "$@"; do
            # A setting's BIN=... picks the binary (an older build, for before and after).
            bin=$BIN
            for word in $setting; do
                if [[ $word == BIN=* ]]; then bin=${word#BIN=}; fi
            done
            # shellcheck disable=SC2086
            out=$(env $setting "$bin" bench "$scene" --sizes "$SIZE" --spp "$SPP" \
                --depth "$DEPTH" --frames "$FRAMES" --backend gpu 2>/dev/null)
            header=$(sed -n 1,2p <<<"$out")
            sed -n '3,$p' <<<"$out" | sed "s#^|#| $setting | $round |#" >>"$rows"
        done
    done
done
sed -n 1p <<<"$header" | sed 's/^|/| setting | round |/'
sed -n 2p <<<"$header" | sed 's/^|/|---|---:|/'
sort -t'|' -k4,4 -k2,2 -k3,3n "$rows"
