#!/usr/bin/env bash
# gpurt against POV-Ray and Tachyon on five SPD scenes at 512x512, one sample per pixel,
# both cores (WIDTH, HEIGHT, SPP and THREADS change that).
#
# Times each whole process (start-up, parsing, BVH, render, PNG writing) with
# /usr/bin/time, keeps the fastest of REPEAT runs (default 3; the machine may be shared),
# and prints a markdown table. gpurt runs four ways: the default command (--backend
# auto), the CPU backend, and the GPU backend with the driver's shader cache cold and
# warm (failures are ignored: no adapter).
# POV-Ray reads the SPD generators' own POV-Ray versions of the scenes, with the command
# line of ../shared/peers/povray/README.md (-A: no antialiasing, +WT: THREADS threads).
# Tachyon reads the NFF files themselves (-numthreads THREADS, -raydepth 5 as gpurt's default
# depth); it does no refraction, and draws gears-4 all white.
#
# With SPP=n (a square: 4, 9, 16) gpurt traces n jittered samples a pixel, POV-Ray
# supersamples every pixel n times (+A0.0 +AM1 +R<sqrt n>: its threshold 0 makes it
# supersample all pixels, adding its corner samples), and Tachyon traces n - 1 jittered
# samples beside its first (-aasamples n-1: its tracing time grows with them as ours does).
#
# Usage: benches/peers.sh            (from anywhere; needs povray, tachyon and ../shared)
#        REPEAT=5 benches/peers.sh
#        WIDTH=1920 HEIGHT=1080 SPP=4 NO_GPU=1 benches/peers.sh balls-4 gears-4 teapot-6
#        (NO_GPU=1 leaves out the two --backend gpu columns; scenes: a subset of the five)
#        THREADS=1 REPEAT=1 benches/peers.sh  (every program on one thread: gpurt --threads,
#        POV-Ray +WT, Tachyon -numthreads; default: one a core)
set -euo pipefail

ROOT=$(cd "$(dirname "$0")/.." && pwd)
SCENES_DIR="$ROOT/../shared/scenes/spd"
POV_DIR="$ROOT/../shared/peers/povray"
SCENES=(balls-4 gears-4 mount-7 teapot-6 tree-11)
if [[ $# -gt 0 ]]; then SCENES=("$@"); fi
WIDTH=${WIDTH:-512}
HEIGHT=${HEIGHT:-512}
SPP=${SPP:-1}
REPEAT=${REPEAT:-3}
THREADS=${THREADS:-$(nproc)}
POV_AA=(-A)
if [[ $SPP -gt 1 ]]; then
    n=$(awk -v s="$SPP" 'BEGIN{n = int(sqrt(s) + 0.5); print (n * n == s) ? n : 0}')
    [[ $n -gt 0 ]] || { echo "SPP must be a square (4, 9, 16, ...)" >&2; exit 2; }
    POV_AA=(+A0.0 +AM1 "+R$n")
fi
SIZE_ARGS=(--width "$WIDTH" --height "$HEIGHT" --spp "$SPP" --threads "$THREADS")
TIME=/usr/bin/time

if [[ ! -x $TIME ]]; then
    echo "installing GNU time" >&2
    apt-get install -y time >/dev/null
fi
command -v povray >/dev/null || { echo "povray is not installed" >&2; exit 2; }
command -v tachyon >/dev/null || { echo "tachyon is not installed (apt-get install tachyon)" >&2; exit 2; }
[[ -d $SCENES_DIR && -d $POV_DIR ]] || { echo "missing $SCENES_DIR or $POV_DIR" >&2; exit 2; }

(cd "$ROOT" && cargo build --release --quiet)
GPURT="$ROOT/target/release/gpurt"

WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT

# Runs a command REPEAT times under /usr/bin/time; prints "best_wall peak_kb log_file" of
# the fastest run (the log holds the command's stderr, the time line last). Fails when the
# command fails.
timed() {
    local best="" best_kb="" best_log="" i log line wall kb
    for ((i = 0; i < REPEAT; i++)); do
        log=$(mktemp "$WORK/run.XXXXXX")
        "$TIME" -f "TIME %e %M" "$@" >/dev/null 2>"$log" || return 1
        line=$(grep '^TIME ' "$log" | tail -1)
        wall=$(awk '{print $2}' <<<"$line")
        kb=$(awk '{print $3}' <<<"$line")
        if [[ -z $best ]] || awk -v a="$wall" -v b="$best" 'BEGIN{exit !(a < b)}'; then
            best=$wall best_kb=$kb best_log=$log
        fi
    done
    echo "$best $best_kb $best_log"
}

mb() { awk -v k="$1" 'BEGIN{printf "%.0f", k / 1024}'; }

rows=()
adapter=""
for s in "${SCENES[@]}"; do
    echo "== $s" >&2
    out=$(timed "$GPURT" "$SCENES_DIR/$s.nff" -o "$WORK/$s-cpu.png" \
        "${SIZE_ARGS[@]}" --backend cpu --stats) || { echo "gpurt failed on $s" >&2; exit 1; }
    read -r g_wall g_kb g_log <<<"$out"
    g_mrays=$(grep -o '[0-9.]* Mrays/s' "$g_log" | awk '{print $1}')

    out=$(timed "$GPURT" "$SCENES_DIR/$s.nff" -o "$WORK/$s-auto.png" \
        "${SIZE_ARGS[@]}") || { echo "gpurt failed on $s" >&2; exit 1; }
    read -r a_wall a_kb _ <<<"$out"
    default_backend=$("$GPURT" "$SCENES_DIR/$s.nff" -o "$WORK/$s-auto.png" "${SIZE_ARGS[@]}" \
        -v 2>&1 | awk '$1 == "backend" {print $2}' | tr -d ':,')

    # The GPU backend twice: with Mesa's shader cache cold (a new, empty cache directory
    # for every run, and gpurt's own pipeline cache off), and warm (a cache directory
    # that one untimed run has filled).
    gpu_cell="-" cold_cell="-" u_wall="" c_wall=""
    gpu=("$GPURT" "$SCENES_DIR/$s.nff" -o "$WORK/$s-gpu.png" "${SIZE_ARGS[@]}"
        --backend gpu --stats -v)
    if [[ -z ${NO_GPU:-} ]] && out=$(timed sh -c 'MESA_SHADER_CACHE_DIR=$(mktemp -d -p "$0") GPURT_CACHE_DIR= exec "$@"' \
        "$WORK" "${gpu[@]}"); then
        read -r c_wall _ c_log <<<"$out"
        c_shader=$(awk '$1 == "shader" {print $2}' "$c_log")
        cold_cell="$c_wall ($c_shader compiling)"
        mkdir -p "$WORK/mesa-$s"
        MESA_SHADER_CACHE_DIR="$WORK/mesa-$s" "${gpu[@]}" 2>/dev/null
        out=$(timed env MESA_SHADER_CACHE_DIR="$WORK/mesa-$s" "${gpu[@]}")
        read -r u_wall _ u_log <<<"$out"
        u_mrays=$(grep -o '[0-9.]* Mrays/s' "$u_log" | awk '{print $1}')
        adapter=$(awk '$1 == "gpu" {$1 = ""; print substr($0, 2); exit}' "$u_log") || true
        gpu_cell="$u_wall ($u_mrays Mrays/s)"
    fi

    out=$(timed tachyon "$SCENES_DIR/$s.nff" -res "$WIDTH" "$HEIGHT" -numthreads "$THREADS" -raydepth 5 \
        -aasamples $((SPP - 1)) -format PNG -o "$WORK/$s-tachyon.png") || { echo "tachyon failed on $s" >&2; exit 1; }
    read -r t_wall t_kb _ <<<"$out"

    gunzip -c "$POV_DIR/$s.pov.gz" >"$WORK/$s.pov"
    # POV-Ray resolves relative names against the current directory.
    out=$(cd "$WORK" && timed povray "+I$s.pov" "+O$s-pov.png" \
        "+W$WIDTH" "+H$HEIGHT" "${POV_AA[@]}" "+WT$THREADS" -D +FN) || { echo "povray failed on $s" >&2; exit 1; }
    read -r p_wall p_kb p_log <<<"$out"

    ratio() { [[ -n $1 ]] && awk -v a="$1" -v b="$2" 'BEGIN{printf "%.2f", a / b}' || echo -; }
    rows+=("| $s | $a_wall ($default_backend) | $(mb "$a_kb") | $g_wall | $g_mrays | $(mb "$g_kb") | $cold_cell | $gpu_cell | $p_wall | $(mb "$p_kb") | $t_wall | $(mb "$t_kb") | $(ratio "$a_wall" "$p_wall") | $(ratio "$a_wall" "$t_wall") | $(ratio "$c_wall" "$p_wall") | $(ratio "$u_wall" "$p_wall") |")
done

echo
echo "| scene | gpurt (default) wall s | peak MB | --backend cpu wall s | Mrays/s | peak MB | --backend gpu, cold cache, wall s | --backend gpu, warm, wall s | POV-Ray wall s | peak MB | Tachyon wall s | peak MB | default / POV-Ray | default / Tachyon | gpu cold / POV-Ray | gpu warm / POV-Ray |"
echo "|---|---:|---:|---:|---:|---:|---|---|---:|---:|---:|---:|---:|---:|---:|---:|"
printf '%s\n' "${rows[@]}"
echo
echo "${WIDTH}x${HEIGHT}, $SPP spp (POV-Ray: ${POV_AA[*]}), $THREADS threads; best of $REPEAT runs. Wall time and peak memory are"
echo "of the whole process; the ratios are of wall times (below 1: gpurt is faster)."
if [[ -n $adapter ]]; then echo "--backend gpu runs on: $adapter."; fi
