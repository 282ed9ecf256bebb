#!/usr/bin/env bash
# Peak memory of whole renders against what the scene holds: a 2M-triangle terrain and a
# field of 1M spheres (`examples/field.rs`, also the terrain as OBJ and binary STL, gzip,
# and binary PLY),
# and files that are nearly all comment lines around one sphere: 3 GB gzip-compressed and
# 1 GB plain. Each is rendered at SIZE x SIZE, 1 spp, by the release gpurt on each backend
# and, when BASELINE names another gpurt binary (an older build), by that one too, side by
# side in the same run (interleaved, best of REPEAT for the times). Prints a markdown table:
# exit code, parse, build and render seconds (as --stats prints them: a CPU-only render
# builds its eight-wide tree and triangle blocks in the build step; builds before that
# did in the render), the whole process's wall time, peak memory (VmHWM, as --stats
# prints it; else /usr/bin/time's max RSS) and peak bytes per primitive. Files are
# generated into a temporary folder and deleted at the end (the comment files need 4 GB of disk while they
# exist).
#
#   benches/scene-memory.sh
#   BASELINE=/path/to/old/gpurt REPEAT=3 benches/scene-memory.sh
#   TERRAIN=500 SPHERES=500 COMMENTS_GZ_MB=300 COMMENTS_PLAIN_MB=100 BACKENDS=cpu benches/scene-memory.sh
#   GPURT=/path/to/gpurt FIELD=/path/to/field benches/scene-memory.sh   (given builds, nothing built)
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
SIZE=${SIZE:-256}
TERRAIN=${TERRAIN:-1000}
SPHERES=${SPHERES:-1000}
COMMENTS_GZ_MB=${COMMENTS_GZ_MB:-3000}
COMMENTS_PLAIN_MB=${COMMENTS_PLAIN_MB:-1000}
BACKENDS=${BACKENDS:-cpu gpu}
REPEAT=${REPEAT:-1}
BASELINE=${BASELINE:-}
if [ -z "${GPURT:-}" ] || [ -z "${FIELD:-}" ]; then
    (cd "$ROOT" && cargo build --release --quiet --bin gpurt --example field)
fi
GPURT=${GPURT:-$ROOT/target/release/gpurt}
FIELD=${FIELD:-$ROOT/target/release/examples/field}
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
ROWS="$WORK/rows.tsv"
: >"$ROWS"

# The scenes, as "name file prims".
"$FIELD" terrain "$TERRAIN" nff >"$WORK/terrain.nff"
"$FIELD" terrain "$TERRAIN" obj | gzip -1 >"$WORK/terrain.obj.gz"
"$FIELD" terrain "$TERRAIN" stl | gzip -1 >"$WORK/terrain.stl.gz"
"$FIELD" terrain "$TERRAIN" ply >"$WORK/terrain.ply"
"$FIELD" spheres "$SPHERES" >"$WORK/spheres.nff"
sphere='v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 40\nl 1 1 1\nf 1 0 0 1 0 1 0 1\ns 0 0 0 1\n'
comments() { # MB
    printf "$sphere"
    # `yes` ends on the broken pipe, which is no failure here.
    { yes '# a comment line of the kind an exporter writes by the million' || true; } |
        head -c "$(($1 * 1000 * 1000))"
}
comments "$COMMENTS_GZ_MB" | gzip -1 >"$WORK/comments.nff.gz"
comments "$COMMENTS_PLAIN_MB" >"$WORK/comments.nff"
tris=$((2 * TERRAIN * TERRAIN))
scenes=(
    "terrain terrain.nff $tris"
    "terrain-obj terrain.obj.gz $tris"
    "terrain-stl terrain.stl.gz $tris"
    "terrain-ply terrain.ply $tris"
    "spheres spheres.nff $((SPHERES * SPHERES))"
    "comments-${COMMENTS_GZ_MB}MB-gz comments.nff.gz 1"
    "comments-${COMMENTS_PLAIN_MB}MB comments.nff 1"
)
bins=("new $GPURT")
[ -n "$BASELINE" ] && bins+=("old $BASELINE")

secs() { awk -v k="$1" '$1 == k && $3 ~ /^s,?$/ { print $2; exit }' "$2"; }
min() { sort -g | head -n 1; }

for scene in "${scenes[@]}"; do
    read -r name file prims <<<"$scene"
    mb=$(awk -v n="$(stat -c %s "$WORK/$file")" 'BEGIN { printf "%.1f", n / 1e6 }')
    for backend in $BACKENDS; do
        # Meshes and comments are read the same on both backends: the CPU tells it.
        [ "$backend" != cpu ] && [ "$name" != terrain ] && [ "$name" != spheres ] && continue
        declare -A parse=() build=() render=() wall=() peak=() rc=()
        for _ in $(seq "$REPEAT"); do
            for b in "${bins[@]}"; do
                read -r tag bin <<<"$b"
                log="$WORK/$tag.log"
                code=0
                /usr/bin/time -f "%e %M" -o "$WORK/time" "$bin" "$WORK/$file" --width "$SIZE" \
                    --height "$SIZE" --spp 1 --backend "$backend" --stats \
                    -o "$WORK/out.png" >/dev/null 2>"$log" || code=$?
                rss=$(tail -n 1 "$WORK/time" | awk '{ print $2 }')
                wall[$tag]="${wall[$tag]:-} $(tail -n 1 "$WORK/time" | awk '{ print $1 }')"
                render[$tag]="${render[$tag]:-} $(awk -v k="$backend" '$1 == k && $3 == "s," { print $2; exit }' "$log")"
                vm=$(awk '$1 == "peak" { print $3; exit }' "$log")
                p=${vm:-$(awk -v k="$rss" 'BEGIN { print k / 1024 }')}
                rc[$tag]=$code
                [ "$code" -ne 0 ] && rc[$tag]="$code: $(grep -v '^\s*$' "$log" | tail -n 1 | tr '|\t' '/ ' | cut -c1-120)"
                parse[$tag]="${parse[$tag]:-} $(secs parse "$log")"
                build[$tag]="${build[$tag]:-} $(secs build "$log")"
                peak[$tag]="${peak[$tag]:-} $p"
                echo "done: $name $backend $tag (exit $code)" >&2
            done
        done
        for b in "${bins[@]}"; do
            read -r tag _ <<<"$b"
            best() { tr ' ' '\n' <<<"$1" | grep -v '^$' | min; }
            printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$name" "$prims" "$mb" \
                "$backend" "$tag" "${rc[$tag]}" "$(best "${parse[$tag]}")" \
                "$(best "${build[$tag]}")" "$(best "${peak[$tag]}")" "$(best "${render[$tag]}")" \
                "$(best "${wall[$tag]}")" >>"$ROWS"
            echo "row: $(tail -n 1 "$ROWS")" >&2
        done
        unset parse build render wall peak rc
    done
done

echo
echo "${SIZE}x${SIZE}, 1 spp; times best of $REPEAT; peak = the process's peak resident memory"
echo
awk -F '\t' '
function num(x, f) { return x == "" ? "-" : sprintf(f, x) }
BEGIN {
    print "| scene | prims | file MB | backend | gpurt | exit | parse s | build s | render s | wall s | peak MiB | peak bytes/prim |"
    print "|---|---:|---:|---|---|---|---:|---:|---:|---:|---:|---:|"
}
{
    per = ($2 > 1 && $9 != "") ? sprintf("%.0f", $9 * 1048576 / $2) : "-"
    printf "| %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |\n", $1, $2, $3, $4, $5,
        $6, num($7, "%.2f"), num($8, "%.2f"), num($10, "%.2f"), num($11, "%.2f"),
        num($9, "%.0f"), per
}' "$ROWS"
