#!/usr/bin/env bash
# The BVH's build qualities side by side in one run: for each scene and each quality
# (GPURT_BVH), the build time, the CPU backend's time and Mrays/s, the nodes and node
# bytes a ray of each kind fetched on the CPU's eight-wide walk, and the same counts on
# the GPU backend's walk (whatever adapter `--backend gpu` finds: lavapipe on a machine
# without a GPU; skipped where there is none). Node counts do not depend on the machine
# or its load, so they compare across runs; times only within one.
#
# Usage: benches/trees.sh [SCENE...]
#        QUALITIES="medium high" SIZE=512 SPP=1 DEPTH=5 NO_GPU=1 benches/trees.sh
#        (default scenes: balls-6, gears-4, mount-9, teapot-6 and tree-11 of ../shared,
#        and the glass and mirror scenes of scenes/)
set -euo pipefail

ROOT=$(cd "$(dirname "$0")/.." && pwd)
SPD="$ROOT/../shared/scenes/spd"
QUALITIES=${QUALITIES:-"medium high"}
SIZE=${SIZE:-512}
SPP=${SPP:-1}
DEPTH=${DEPTH:-5}
if [[ $# -eq 0 ]]; then
    set -- "$SPD/balls-6.nff.gz" "$SPD/gears-4.nff" "$SPD/mount-9.nff.gz" "$SPD/teapot-6.nff" \
        "$SPD/tree-11.nff" "$ROOT/scenes/glass.nff" "$ROOT/scenes/mirrors.nff"
fi
(cd "$ROOT" && cargo build --release --quiet)
GPURT="$ROOT/target/release/gpurt"
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT

# `nodes (bytes)` of the `--stats` line of a kind of ray (`cpu eye`, `gpu shadow`, ...).
per_ray() {
    awk -v k="$2" 'index($0, k " ") == 1 {
        for (i = 1; i < NF; i++) {
            if ($(i + 1) == "nodes/ray,") n = $i
            if ($(i + 1) == "node") b = $i
        }
    } END {print (n == "" ? "-" : n " (" b ")")}' <<<"$1"
}
build() { awk '$1 == "build" {print $2; exit}' <<<"$1"; }
# The CPU's render time and Mrays/s (`cpu 1.473 s, 20127714 rays, 13.66 Mrays/s`).
render() { awk '$1 == "cpu" && $3 == "s," {print $2; exit}' <<<"$1"; }
mrays() { awk '$1 == "cpu" && $NF == "Mrays/s" {print $(NF - 1); exit}' <<<"$1"; }

echo "| scene | quality | build s | CPU render s | CPU Mrays/s | CPU eye nodes (B) | CPU shadow | CPU secondary | GPU eye nodes (B) | GPU shadow | GPU secondary |"
echo "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
args=(--width "$SIZE" --height "$SIZE" --spp "$SPP" --depth "$DEPTH" --stats)
for scene in "$@"; do
    name=$(basename "$scene")
    name=${name%%.*}
    for q in $QUALITIES; do
        echo "== $name ($q)" >&2
        cpu=$(GPURT_BVH=$q "$GPURT" "$scene" "${args[@]}" --backend cpu -o "$OUT/cpu.png" 2>&1)
        gpu=""
        if [[ -z ${NO_GPU:-} ]]; then
            gpu=$(GPURT_BVH=$q "$GPURT" "$scene" "${args[@]}" --backend gpu -o "$OUT/gpu.png" 2>&1) || gpu=""
        fi
        echo "| $name | $q | $(build "$cpu") | $(render "$cpu") | $(mrays "$cpu") | $(per_ray "$cpu" "cpu eye") | $(per_ray "$cpu" "cpu shadow") | $(per_ray "$cpu" "cpu secondary") | $(per_ray "$gpu" "gpu eye") | $(per_ray "$gpu" "gpu shadow") | $(per_ray "$gpu" "gpu secondary") |"
    done
done
echo
echo "${SIZE}x${SIZE}, $SPP spp, depth $DEPTH; $(nproc) cores; node bytes: the CPU's eight-wide nodes, the GPU's nodes of its walk."
