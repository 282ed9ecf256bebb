#!/usr/bin/env bash
# Thumbnails of a folder of meshes: scenes per second for one batch process
# (`gpurt DIR/*.obj --out-dir OUT`) against one process per scene, at 256x256.
# The meshes (COUNT of them, default 500: bumpy spheres of a few hundred triangles, as
# OBJ) are generated into a temporary folder and deleted afterwards.
#
#   benches/batch.sh            COUNT=200 BACKEND=gpu benches/batch.sh
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
COUNT=${COUNT:-500}
BACKEND=${BACKEND:-auto}
(cd "$ROOT" && cargo build --release --quiet)
GPURT="$ROOT/target/release/gpurt"
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
python3 - "$WORK/meshes" "$COUNT" <<'PY'
import math, os, random, sys
out, count = sys.argv[1], int(sys.argv[2])
os.makedirs(out)
for k in range(count):
    rnd = random.Random(k)
    rings, segs = rnd.randint(8, 16), rnd.randint(12, 24)
    bumps = [rnd.uniform(0.0, 0.25) for _ in range(4)]
    lines = []
    for i in range(rings + 1):
        th = math.pi * i / rings
        for j in range(segs):
            ph = 2 * math.pi * j / segs
            r = 1 + bumps[0] * math.sin(3 * th + bumps[1] * 10) * math.cos(2 * ph + bumps[2] * 10)
            lines.append("v %.5f %.5f %.5f" % (r * math.sin(th) * math.cos(ph), r * math.sin(th) * math.sin(ph), r * math.cos(th)))
    for i in range(rings):
        for j in range(segs):
            a, b = i * segs + j + 1, i * segs + (j + 1) % segs + 1
            c, d = a + segs, b + segs
            lines.append("f %d %d %d" % (a, b, d))
            lines.append("f %d %d %d" % (a, d, c))
    open(os.path.join(out, "part-%04d.obj" % k), "w").write("\n".join(lines) + "\n")
PY
SIZE=(--width 256 --height 256 --backend "$BACKEND")
# One render first, so that both ways find the shader compiled (Mesa's cache), as any
# launch after the first does.
"$GPURT" "$WORK/meshes/part-0000.obj" -o "$WORK/warm.png" "${SIZE[@]}" 2>/dev/null
start=$(date +%s.%N)
"$GPURT" "$WORK"/meshes/*.obj --out-dir "$WORK/batch" "${SIZE[@]}" 2>/dev/null
mid=$(date +%s.%N)
mkdir -p "$WORK/single"
for f in "$WORK"/meshes/*.obj; do
    "$GPURT" "$f" -o "$WORK/single/$(basename "$f" .obj).png" "${SIZE[@]}" 2>/dev/null
done
end=$(date +%s.%N)
# The two ways must write the same images.
for f in "$WORK"/batch/*.png; do cmp -s "$f" "$WORK/single/$(basename "$f")" || { echo "differs: $f" >&2; exit 1; }; done
awk -v n="$COUNT" -v a="$start" -v b="$mid" -v c="$end" 'BEGIN {
    printf "| way | %d meshes at 256x256 | scenes/s |\n|---|---:|---:|\n", n
    printf "| one batch process | %.2f s | %.1f |\n", b - a, n / (b - a)
    printf "| one process per scene | %.2f s | %.1f |\n", c - b, n / (c - b)
}'
echo
echo "backend: $BACKEND; $(nproc) threads; identical images both ways."
