#!/usr/bin/env bash
# gpurt's CPU traversal against Embree 3 on the same rays, in one run: the primary rays of
# a SIZE x SIZE render (one a pixel, centres, in 4x4 blocks), the shadow rays from their
# hits to each point light, and mirror rays off every hit (the incoherent rays that keep
# the single-ray walk). `examples/rays.rs` traces them with our `closest_hit` and
# `transmission` one at a time and in packets (`cpu::packet`, the kernels GPURT_SIMD or
# the processor picks), checks that both give the same answers, and writes the rays out;
# `benches/embree/rays.c` traces the same file with Embree's rtcIntersect1/8/16 and
# rtcOccluded1/8/16 (the shadow rays twice: stopping at the first surface, and going on
# through transmitting ones by an occlusion filter, as ours do) and says how often its
# answers match ours. Prints markdown tables.
#
#   benches/embree.sh [SCENE...]      (default: the six SPD scenes below, 1024x1024, 2 threads)
#   THREADS=1 SIZE=512 benches/embree.sh
#   CLOCK=cpu benches/embree.sh       (processor time instead of wall-clock, both sides: on a
#                                      machine shared with other work)
#   GPURT_SIMD=sse benches/embree.sh  (our packets in SSE's four lanes)
#   SPP=16 benches/embree.sh          (our side traces the tree gpurt builds for a 16-sample
#                                      render; the rays are the same)
#   GPURT_BVH=high benches/embree.sh  (our side on its high-quality tree, whatever the size)
#   REPEAT=3 benches/embree.sh        (each scene's programs run three times in turn, ours then
#                                      Embree's two builds, and each figure the best of them: a
#                                      machine whose speed swings disturbs one run, not all)
#
# Embree builds its tree twice: at its default (medium) quality for every table, and at
# RTC_BUILD_QUALITY_HIGH (spatial splits; EMBREE_QUALITY=high to benches/embree/rays.c)
# for a second column of the mirror rays' table.
#
# On a machine with AVX-512 the tables are taken twice in the same run: each side at its
# widest, then both held to AVX2 (GPURT_SIMD=avx2, Embree's device config isa=avx2).
#
# Needs Debian's libembree-dev (skipped with a message when it is missing) and ../shared.
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
THREADS=${THREADS:-2}
REPEAT=${REPEAT:-1}
SIZE=${SIZE:-1024}
if [[ ! -f /usr/include/embree3/rtcore.h ]]; then
    echo "skipped: Embree 3 is not installed (apt-get install -y libembree-dev)" >&2
    exit 0
fi
if [ $# -eq 0 ]; then
    set -- "$ROOT"/../shared/scenes/spd/{balls-4,gears-4,mount-7,teapot-6,tree-11,rings-7}.nff
fi
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
cc -O3 -march=native -o "$WORK/rays" "$ROOT/benches/embree/rays.c" -lembree3 -lpthread -lm
(cd "$ROOT" && cargo build --release --quiet --example rays)

# `name count rate` triples: the count and the rate after `name`; over the REPEAT runs'
# lines, the first count and the best rate. (`count` also reads `lanes N` and `isa X`.)
count() { awk -v k="$2" '{for (i = 1; i < NF; i++) if ($i == k) {print $(i + 1); exit}}' <<<"$1"; }
rate() { awk -v k="$2" '{for (i = 1; i < NF; i++) if ($i == k && (m == "" || $(i + 2) + 0 > m + 0)) m = $(i + 2)} END{print m}' <<<"$1"; }
ratio() { awk -v a="$1" -v b="$2" 'BEGIN{printf "%.2f", a / b}'; }
best() { awk 'BEGIN{m = 0} {for (i = 1; i <= NF; i++) if ($i > m) m = $i} END{print m}' <<<"$*"; }
# Embree's build time in seconds, from its summary line (`build 0.011 s`): the shortest.
built() { grep -o 'build [0-9.]* s' <<<"$1" | awk '{print $2}' | sort -g | head -1; }

# The tables for one instruction set: `default` (each side's widest), or `avx2` (both held
# to AVX2: GPURT_SIMD=avx2, Embree's device config isa=avx2), so that a machine with
# AVX-512 gives the AVX2 figures of most users' machines in the same run.
tables() {
    local set=$1 simd=${GPURT_SIMD:-} config=""
    shift
    [ "$set" = avx2 ] && simd=avx2 config=avx2
    primary=() shadow=() mirror=() agree=()
    lanes="" isa=""
    for scene in "$@"; do
        name=$(basename "$scene" .gz)
        name=${name%.nff}
        echo "== $name ($set)" >&2
        ours="" theirs="" high=""
        for _ in $(seq "$REPEAT"); do
            ours+=$(GPURT_SIMD=$simd RAYON_NUM_THREADS=$THREADS "$ROOT/target/release/examples/rays" "$scene" "$SIZE" "$WORK/$name.rays")$'\n'
            theirs+=$("$WORK/rays" "$WORK/$name.rays" "$THREADS" $config)$'\n'
            # Embree's high-quality build (spatial splits), for the mirror rays' table.
            high+=$(EMBREE_QUALITY=high "$WORK/rays" "$WORK/$name.rays" "$THREADS" $config)$'\n'
        done
        lanes=$(count "$ours" lanes) isa=$(count "$ours" isa)
        g1=$(rate "$ours" primary1) gp=$(rate "$ours" primaryP)
        e1=$(rate "$theirs" primary1) e8=$(rate "$theirs" primary8) e16=$(rate "$theirs" primary16)
        primary+=("| $name | $(count "$ours" primary1) | $g1 | $gp | $e1 | $e8 | $e16 | $(ratio "$g1" "$e1") | $(ratio "$gp" "$(best "$e1 $e8 $e16")") |")
        s1=$(rate "$ours" shadow1) sp=$(rate "$ours" shadowP)
        o1=$(rate "$theirs" shadow1) o8=$(rate "$theirs" shadow8) o16=$(rate "$theirs" shadow16)
        t1=$(rate "$theirs" through1) t8=$(rate "$theirs" through8) t16=$(rate "$theirs" through16)
        shadow+=("| $name | $(count "$ours" shadow1) | $s1 | $sp | $o1, $o8, $o16 | $t1, $t8, $t16 | $(ratio "$s1" "$t1") | $(ratio "$sp" "$(best "$t8 $t16")") | $(ratio "$sp" "$o16") |")
        m1=$(rate "$ours" mirror1) em=$(rate "$theirs" mirror1) eh=$(rate "$high" mirror1)
        mirror+=("| $name | $(count "$ours" mirror1) | $m1 | $em | $eh | $(built "$theirs") / $(built "$high") | $(ratio "$m1" "$em") | $(ratio "$m1" "$eh") |")
        a=$(grep -m1 '^agree' <<<"$theirs")
        agree+=("| $name | $(count "$a" primary1), $(count "$a" primary8), $(count "$a" primary16) | $(count "$a" shadow1), $(count "$a" shadow8), $(count "$a" shadow16) | $(count "$a" through1), $(count "$a" through8), $(count "$a" through16) | $(count "$a" mirror1) |")
    done

    echo "### $(if [ "$set" = avx2 ]; then echo "AVX2 on this AVX-512 machine (GPURT_SIMD=avx2, Embree's isa=avx2)"; else echo "This machine's widest instruction set (gpurt: $isa; Embree: its default)"; fi)"
    echo
    echo "Primary rays, Mrays/s (one a pixel; Embree's packets: 8 = half a 4x4 block, 16 = the block):"
    echo
    echo "| scene | rays | gpurt one at a time | gpurt packets of $lanes ($isa) | Embree rtcIntersect1 | rtcIntersect8 | rtcIntersect16 | gpurt 1 / Embree 1 | packets / Embree's best |"
    echo "|---|---:|---:|---:|---:|---:|---:|---:|---:|"
    printf '%s\n' "${primary[@]}"
    echo
    echo "Shadow rays to point lights, Mrays/s (a packet: one block's rays to one light). Ours go on"
    echo "through surfaces that transmit light; Embree's rtcOccluded stops at the first surface, and"
    echo "through the second scene (transmitting primitives with an occlusion filter) gives our answers:"
    echo
    echo "| scene | rays | gpurt one at a time | gpurt packets of $lanes | Embree rtcOccluded1, 8, 16 (stops at any surface) | Embree through transmitting surfaces 1, 8, 16 | gpurt 1 / Embree through 1 | packets / Embree's best through | packets / rtcOccluded16 |"
    echo "|---|---:|---:|---:|---:|---:|---:|---:|---:|"
    printf '%s\n' "${shadow[@]}"
    echo
    echo "Mirror rays off every hit (incoherent: one at a time on both sides), Mrays/s:"
    echo
    echo "| scene | rays | gpurt | Embree rtcIntersect1 | rtcIntersect1, high-quality build | Embree build s, medium / high | gpurt / Embree | gpurt / Embree high |"
    echo "|---|---:|---:|---:|---:|---|---:|---:|"
    printf '%s\n' "${mirror[@]}"
    echo
    echo "Embree's answers that agree with ours, % of rays (hit distance within 1e-4; shadow: blocked or not;"
    echo "through: blocked or not, and the light let through, each channel within 1e-4):"
    echo
    echo "| scene | primary 1, 8, 16 | shadow 1, 8, 16 | through 1, 8, 16 | mirror |"
    echo "|---|---|---|---|---|"
    printf '%s\n' "${agree[@]}"
    echo
}

tables default "$@"
if grep -qw avx512f /proc/cpuinfo; then
    echo
    tables avx2 "$@"
else
    echo "(No AVX-512 here: the table above is AVX2's.)"
    echo
fi
echo "${SIZE}x${SIZE}, $THREADS threads on both sides, chunks of 64 rays, best of five runs$([ "$REPEAT" -gt 1 ] && echo " in each of $REPEAT turns")"
echo "(${CLOCK:-wall}-clock time). Embree 3: spheres as SPHERE_POINT, cones as user geometry (our"
echo "intersection in C, lane by lane). gpurt: closest_hit / transmission and cpu::packet; our"
echo "shadow rays go on through surfaces that transmit light, Embree's occlusion test stops (its"
echo "'through' figures let its rays through them by an occlusion filter, giving our answers)."
