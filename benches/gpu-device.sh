#!/usr/bin/env bash
# Checks and times gpurt on a machine with a real GPU but no Rust toolchain, in one
# command, from the repository root. What it needs is built elsewhere and carried in
# `.device/` (see `benches/gpu-device-pack.sh`): stripped binaries `gpurt` and
# `gpurt-tests` (the integration tests), `gpurt-debug` (the binary the CLI tests run) and
# `shared.tar.xz` (the scenes the tests read); `.gl/` holds the Vulkan loader packages.
#
# Usage: benches/gpu-device.sh [collapse] [stack] [wavefront] [pooled] [goals] [compile] [qwide] [tune] [images] [bench] [quick] [tests] [loss] [huge]
#        (default: wavefront images bench tests, run in that order whatever the order given)
# Output goes to $OUT (or ./device-out): wavefront-*.md, images.log, bench.md, bench.log,
# tests.log, huge.log. `wavefront` times the seven scenes on the GPU through the one
# kernel and through the wavefront kernels (GPURT_KERNELS), one after the other (with
# each wavefront kernel's GPU time a frame, from timestamp queries), renders balls-4 at
# 1080p both ways for `gpurt diff`, then times waves of 4 GiB (GPURT_WAVE_BYTES) on
# balls-4 and mount-9 at 4K; each of its benches stops after WAVE_TIMEOUT seconds (180 by
# default; half that for the 4 GiB waves), keeping the rows measured by then. `pooled`
# times the seven scenes through the one kernel's `main` and `pooled` entry points
# (GPURT_KERNELS; pooled squares of 16 and 32 pixels, GPURT_POOL_SIDE) at 1 and 16 spp,
# then balls-6 and mount-9 at 4K and 1 spp on the high-quality tree (GPURT_BVH=high),
# through `main` and `pooled`. `goals` benches balls-6 and mount-9 alone (where the
# issue's goals were last missed) at both sizes and sample counts, GPU only, on the usual
# tree and on the high-quality one. `collapse` benches the seven scenes, GPU only, at
# 1080p and 4K, 1 and 16 spp, on the wide trees of the greedy collapse (the default)
# and then of the SAH-optimal one (GPURT_COLLAPSE=optimal), each capped at
# COLLAPSE_TIMEOUT seconds (150 by default). `stack` benches balls-4, gears-4, mount-7
# and teapot-6 at 4K, 1 and 16 spp, GPU only, on the greedy trees, then on the greedy
# trees with a stack of at least 40 entries (GPURT_STACK), then on the optimal trees,
# each capped at STACK_TIMEOUT seconds (120). `compile` prints each walk's and kernel's cold
# compile time (the driver's shader cache off) on five scenes. `qwide` times the seven scenes on the quantised four-wide
# walk (GPURT_TRAVERSAL=qwide) through `main` and `pooled`, at 1 and 16 spp, beside the
# `pooled` step's rows on the wide walk. `tune` runs `gpurt tune` on the seven scenes at
# 1080p and 4K at 1 spp and at 4K at 16 spp, each into a cache directory of its own under
# $OUT (tune-SIZE-SPP/, the kept file included; tune-*.md the tables). `images` renders three scenes at 4K with the scene
# read from textures and from storage buffers (GPURT_FETCH) and compares the PNGs byte
# for byte. `tests` runs the integration tests under a limit (TESTS_TIMEOUT seconds, 300
# by default; a fresh H200 runs them in about 110 s, its shaders compiled cold) and, if
# they do not finish, lists the tests that had not reported, so that a hang costs no more
# than the limit and still says where it was (and `stall.txt`, where each thread waited,
# its kernel stack and its own); TEST_THREADS sets its threads (the cores by default).
# `loss` looks for what stalls the GPU when a device is destroyed with work in flight
# (a command beside fifteen busy ones, then the GPU tests with both device-loss tests).
# `huge` generates SPD mount-10, mount-11 and balls-7 (examples/spd.rs, carried as
# .device/spd) and renders each at 3840x2160 on the GPU and on the CPU backend.
# SMOKE=1 runs the `wavefront`, `pooled`, `qwide`, `tune` and `images` steps at thumbnail sizes, e.g. here on lavapipe
# after packing (`SMOKE=1 GPURT_ADAPTER=llvmpipe benches/gpu-device.sh wavefront images`),
# to check the script before a device runs it.
set -uo pipefail

OUT=${OUT:-$PWD/device-out}
mkdir -p "$OUT"
what=${*:-wavefront images bench tests}
sizes=1920x1080,3840x2160 spps=1,16 hd=(1920 1080) uhd=(3840 2160)
if [[ -n ${SMOKE:-} ]]; then
    sizes=96x54,192x108 spps=1,2 hd=(96 54) uhd=(192 108)
fi

for f in .device/gpurt*.xz; do [[ -e $f ]] && xz -dkf "$f"; done
chmod +x .device/gpurt* 2>/dev/null
if ! ldconfig -p | grep -q libvulkan.so.1; then
    for f in .gl/*.deb; do dpkg -x "$f" /; done
    ldconfig
fi
# eu-stack (for stall.txt) and its libraries, unpacked apart, replacing nothing.
eu=/tmp/gpurt-elfutils
if [[ ! -x $eu/usr/bin/eu-stack ]]; then
    for f in .gl/elfutils/*.deb; do [[ -e $f ]] && dpkg -x "$f" "$eu"; done
fi
if [[ -f /usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json ]]; then
    export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
fi
nvidia-smi --query-gpu=name,driver_version,memory.used,memory.total,clocks.sm,clocks.max.sm --format=csv || true

# The test binary looks for its checkout (CARGO_MANIFEST_DIR) where it was built.
manifest=$(cat .device/manifest-dir)
if [[ $manifest != "$PWD" ]]; then
    mkdir -p "$(dirname "$manifest")"
    ln -sfn "$PWD" "$manifest"
fi
# The scenes beside the checkout, as the tests expect them: unpacked where missing, and
# never replaced (here, on the machine that packed them, they are the originals).
if [[ ! -d $manifest/../shared/scenes ]]; then
    tar -C "$manifest/.." -xJf .device/shared.tar.xz
fi
mkdir -p target/debug target/tmp
cp .device/gpurt-debug target/debug/gpurt

export GPURT_REQUIRE_GPU=1 CI=true GPURT_ADAPTER=${GPURT_ADAPTER:-nvidia}
./.device/gpurt "$manifest/scenes/spheres.nff" -o "$OUT/spheres.png" -v --stats 2>&1


# Each thread of process $1 and of its descendants: its name (a test thread is named for
# its test, cut to 15 characters), its state and the kernel function it waits in, then
# its kernel stack (readable as root): whether a stalled test waits on a lock of its own
# process (futex) or in the driver (ioctl, poll).
stall_dump() {
    local p t
    for p in "$1" $(pgrep -P "$1"); do
        echo "process $p: $(tr '\0' ' ' <"/proc/$p/cmdline" 2>/dev/null | cut -c1-200)"
        for t in /proc/"$p"/task/*; do
            echo "  task ${t##*/} $(cat "$t/comm" 2>/dev/null | tr ' ' '_')" \
                "$(awk '{print $3}' "$t/stat" 2>/dev/null) $(cat "$t/wchan" 2>/dev/null)"
            sed 's/^/      /' "$t/stack" 2>/dev/null | head -12
        done
        # Each thread's own stack, by function (the binaries keep their symbol tables).
        if [[ -x $eu/usr/bin/eu-stack ]]; then
            echo "  stacks of process $p:"
            LD_LIBRARY_PATH=$eu/usr/lib/x86_64-linux-gnu timeout 60 "$eu/usr/bin/eu-stack" \
                -p "$p" 2>&1 | sed 's/^/    /'
        fi
    done
}

spd="$manifest/../shared/scenes/spd"
scenes=()
for s in balls-4 gears-4 mount-7 teapot-6 tree-11 balls-6 mount-9; do
    scenes+=("$(ls "$spd/$s".nff* | head -1)")
done

if [[ $what == *collapse* ]]; then
    # The GPU's wide trees gathered greedily and SAH-optimally, one after the other on one
    # binary: rates by ray kind and the nodes a ray fetched, counted on the device.
    echo "== collapse"
    for c in greedy optimal; do
        GPURT_COLLAPSE=$c timeout "${COLLAPSE_TIMEOUT:-150}" ./.device/gpurt bench "${scenes[@]}" \
            --sizes "$sizes" --spp "$spps" --frames 3 --backend gpu >"$OUT/collapse-$c.md" \
            2>"$OUT/collapse-$c.log"
        echo "$c: exit $?"
        grep -E '^(adapter|traversal|bvh) ' "$OUT/collapse-$c.log"
        cat "$OUT/collapse-$c.md"
    done
fi

if [[ $what == *stack* ]]; then
    # Whether the stack's size is what slowed balls-4 and gears-4 on the optimal trees
    # (docs/speed.md): the greedy trees with the stack they need, then with the 40 entries
    # gears-4's optimal tree needs (32 on the others'), then the optimal trees, one binary.
    echo "== stack"
    four=("${scenes[@]:0:4}")
    for run in greedy-0 greedy-40 optimal-0; do
        collapse=${run%-*} floor=${run#*-}
        # GPURT_STACK empty: the stack each tree needs.
        GPURT_COLLAPSE=$collapse GPURT_STACK=${floor#0} timeout "${STACK_TIMEOUT:-120}" \
            ./.device/gpurt bench "${four[@]}" --sizes 3840x2160 --spp "$spps" --frames 3 \
            --backend gpu >"$OUT/stack-$run.md" 2>"$OUT/stack-$run.log"
        echo "$collapse, stack floor $floor: exit $?"
        grep -E '^(adapter|stack|bvh) ' "$OUT/stack-$run.log"
        cat "$OUT/stack-$run.md"
    done
fi

if [[ $what == *wavefront* ]]; then
    echo "== wavefront"
    for k in main wavefront; do
        # Capped (WAVE_TIMEOUT seconds, 180 by default), so that kernels far slower than
        # hoped leave time for the steps after; the rows measured by then are printed.
        GPURT_KERNELS=$k timeout "${WAVE_TIMEOUT:-180}" ./.device/gpurt bench "${scenes[@]}" \
            --sizes "$sizes" --spp "$spps" --frames 3 --backend gpu >"$OUT/wavefront-$k.md" \
            2>"$OUT/wavefront-$k.log"
        status=$?
        if [[ $status == 124 ]]; then
            echo "$k: stopped after ${WAVE_TIMEOUT:-180} s, the rows so far:"
        else
            echo "$k: exit $status"
        fi
        cat "$OUT/wavefront-$k.md"
        grep 'wavefront kernels' "$OUT/wavefront-$k.log"
        GPURT_KERNELS=$k ./.device/gpurt "${scenes[0]}" -o "/tmp/balls-4-$k.png" --width "${hd[0]}" \
            --height "${hd[1]}" --spp 4 --backend gpu 2>&1 | tail -1
    done
    ./.device/gpurt diff /tmp/balls-4-main.png /tmp/balls-4-wavefront.png 2>&1 | tee "$OUT/wavefront-diff.log"
    # Waves of 4 GiB of records (a million paths and more) against the default 512 MiB.
    GPURT_KERNELS=wavefront GPURT_WAVE_BYTES=$((4 << 30)) timeout $((${WAVE_TIMEOUT:-180} / 2)) \
        ./.device/gpurt bench "${scenes[0]}" \
        "${scenes[6]}" --sizes "${uhd[0]}x${uhd[1]}" --spp 1 --frames 3 --backend gpu 2>&1 |
        tee "$OUT/wavefront-4g.md" | grep '^|'
fi

if [[ $what == *pooled* ]]; then
    # The one kernel through `main` and through `pooled` (a workgroup's square of pixels
    # shared out among its lanes), one after the other, at 1 and 16 spp.
    echo "== pooled"
    for k in main pooled-16 pooled-32; do
        side=16
        [[ $k == *-* ]] && side=${k#*-}
        GPURT_KERNELS=${k%-*} GPURT_POOL_SIDE=$side timeout "${WAVE_TIMEOUT:-180}" \
            ./.device/gpurt bench "${scenes[@]}" --sizes "$sizes" --spp "$spps" --frames 3 \
            --backend gpu >"$OUT/pooled-$k.md" 2>"$OUT/pooled-$k.log"
        echo "$k: exit $?"
        cat "$OUT/pooled-$k.md"
        grep -m1 'kernels:' "$OUT/pooled-$k.log"
        [[ $k == main ]] && grep 'pooled (model)' "$OUT/pooled-$k.log"
    done
    # The eye-ray goal at 4K and 1 spp on the two large scenes, whose one-frame renders
    # get the medium-quality tree, on the high-quality one.
    big=()
    for s in balls-6 mount-9; do big+=("$(ls "$spd/$s".nff* | head -1)"); done
    for k in main pooled; do
        GPURT_BVH=high GPURT_KERNELS=$k timeout "${WAVE_TIMEOUT:-180}" ./.device/gpurt bench \
            "${big[@]}" --sizes "${uhd[0]}x${uhd[1]}" --spp 1 --frames 3 --backend gpu \
            >"$OUT/pooled-high-$k.md" 2>"$OUT/pooled-high-$k.log"
        echo "high, $k: exit $?"
        cat "$OUT/pooled-high-$k.md"
    done
fi

if [[ $what == *goals* ]]; then
    # The issue's goals where they were last missed, the shortest run that reads them:
    # balls-6 (eye rays at 4K, secondary rays) and mount-9 (shadow rays at 1080p, its 4K
    # frame) on the GPU alone, on the tree a render of that length gets and on the
    # high-quality one.
    echo "== goals"
    big=()
    for s in balls-6 mount-9; do big+=("$(ls "$spd/$s".nff* | head -1)"); done
    for bvh in auto high; do
        vars=()
        [[ $bvh == high ]] && vars=(GPURT_BVH=high)
        env "${vars[@]}" timeout "${WAVE_TIMEOUT:-180}" ./.device/gpurt bench \
            "${big[@]}" --sizes "$sizes" --spp "$spps" --frames 3 --backend gpu \
            >"$OUT/goals-$bvh.md" 2>"$OUT/goals-$bvh.log"
        echo "tree $bvh: exit $?"
        grep -E '^(adapter|features|bvh) ' "$OUT/goals-$bvh.log"
        cat "$OUT/goals-$bvh.md"
    done
fi

if [[ $what == *compile* ]]; then
    # How long the driver takes to compile each pipeline cold (its shader cache off, no
    # pipeline cache): the suite compiles every variant, and on a fresh machine its first
    # run took minutes there. A small frame each, so the `shader` line is the compile.
    echo "== compile"
    for s in scenes/spheres.nff scenes/mesh.nff scenes/cones.nff scenes/glass.nff "${scenes[1]}"; do
        for v in wide qwide cwide single pairs pooled wavefront; do
            vars=(GPURT_TRAVERSAL=$v)
            [[ $v == pooled || $v == wavefront ]] && vars=(GPURT_KERNELS=$v)
            vars+=(__GL_SHADER_DISK_CACHE=0 MESA_SHADER_CACHE_DISABLE=true GPURT_CACHE_DIR=)
            line=$(env "${vars[@]}" timeout 120 ./.device/gpurt "$s" -o /tmp/compile.png \
                --width 64 --height 64 --backend gpu --stats 2>&1 | grep '^shader')
            echo "$(basename "$s") $v: ${line:-no shader line (exit or timeout)}"
        done
    done | tee "$OUT/compile.log"
fi

if [[ $what == *qwide* ]]; then
    # The wide walk on nodes of 64 bytes instead of 112, through both entry points.
    echo "== qwide"
    for k in main pooled; do
        GPURT_TRAVERSAL=qwide GPURT_KERNELS=$k timeout "${WAVE_TIMEOUT:-180}" ./.device/gpurt \
            bench "${scenes[@]}" --sizes "$sizes" --spp "$spps" --frames 3 --backend gpu \
            >"$OUT/qwide-$k.md" 2>"$OUT/qwide-$k.log"
        echo "qwide, $k: exit $?"
        cat "$OUT/qwide-$k.md"
        grep -m1 '^traversal' "$OUT/qwide-$k.log"
    done
fi

if [[ $what == *tune* ]]; then
    # Which of the eight strategies `gpurt tune` tries is fastest on this adapter, by
    # setting; each kept file comes back in its own cache directory.
    echo "== tune"
    for setting in "${hd[0]}x${hd[1]} 1" "${uhd[0]}x${uhd[1]} 1" "${uhd[0]}x${uhd[1]} ${spps#*,}"; do
        read -r size spp <<<"$setting"
        GPURT_CACHE_DIR="$OUT/tune-$size-$spp" timeout "${WAVE_TIMEOUT:-180}" ./.device/gpurt \
            tune "${scenes[@]}" --size "$size" --spp "$spp" --frames 3 >"$OUT/tune-$size-$spp.md" \
            2>"$OUT/tune-$size-$spp.log"
        echo "$size, $spp spp: exit $?"
        grep -A10 '^| kernels' "$OUT/tune-$size-$spp.md"
        grep '^chosen' "$OUT/tune-$size-$spp.md"
    done
fi

if [[ $what == *images* ]]; then
    echo "== images"
    for s in balls-4 mount-9 teapot-6; do
        for f in textures buffers; do
            GPURT_FETCH=$f ./.device/gpurt "$(ls "$spd/$s".nff* | head -1)" -o "/tmp/$s-$f.png" \
                --width "${uhd[0]}" --height "${uhd[1]}" --spp 3 --backend gpu 2>&1 | tail -1
        done
        if cmp "/tmp/$s-textures.png" "/tmp/$s-buffers.png"; then
            echo "$s: textures and buffers byte-identical"
        else
            echo "$s: textures and buffers DIFFER"
        fi
    done 2>&1 | tee "$OUT/images.log"
fi

if [[ $what == *bench* ]]; then
    echo "== bench"
    if [[ $what == *quick* ]]; then
        args=(--sizes 1920x1080,3840x2160 --spp 1 --backend gpu)
    else
        args=(--sizes 1920x1080,3840x2160 --spp 1,16 --frames 3)
    fi
    # BINS names other builds in .device/ (or .device/NAME.xz) to time first, GPU only.
    for b in ${BINS:-}; do
        echo "== bench $b"
        ./.device/"$b" bench "${scenes[@]}" --sizes 1920x1080,3840x2160 --spp 1,16 --backend gpu \
            >"$OUT/bench-$b.md" 2>"$OUT/bench-$b.log"
        echo "exit $?"
        cat "$OUT/bench-$b.md"
    done
    ./.device/gpurt bench "${scenes[@]}" "${args[@]}" >"$OUT/bench.md" 2>"$OUT/bench.log"
    echo "exit $?"
    tail -5 "$OUT/bench.log"
    cat "$OUT/bench.md"
fi

if [[ $what == *tests* ]]; then
    echo "== tests"
    # Tests of tools a device machine may lack (there is no package manager's network
    # there) are skipped, and said to be; CI=true would fail them.
    skips=()
    if ! command -v xvfb-run >/dev/null; then
        skips+=(--skip window::)
        echo "skipped, no xvfb-run here: window::"
    fi
    if ! command -v zsh >/dev/null || ! command -v fish >/dev/null; then
        skips+=(--skip cli::shell::completion_scripts)
        echo "skipped, no zsh or fish here: cli::shell::completion_scripts*"
    fi
    if ! command -v groff >/dev/null; then
        skips+=(--skip cli::shell::the_manual_page)
        echo "skipped, no groff here: cli::shell::the_manual_page*"
    fi
    # A stalled GPU fails the tests that wait on it within a minute, each saying so,
    # rather than leaving the run to its timeout.
    GPURT_WAIT_LIMIT=${GPURT_WAIT_LIMIT:-60} ./.device/gpurt-tests \
        --test-threads "${TEST_THREADS:-$(nproc)}" "${skips[@]}" >"$OUT/tests.log" 2>&1 &
    pid=$!
    SECONDS=0
    while kill -0 "$pid" 2>/dev/null && ((SECONDS < ${TESTS_TIMEOUT:-300})); do sleep 1; done
    if kill -0 "$pid" 2>/dev/null; then
        # Stopped making progress (docs/gpu.md, "A suite that stopped"): where each thread of
        # the test process and of the processes it started waits, before they are killed.
        stall_dump "$pid" >"$OUT/stall.txt" 2>&1
        pkill -KILL -P "$pid" 2>/dev/null
        kill -KILL "$pid" 2>/dev/null
        wait "$pid" 2>/dev/null
        status=124
    else
        wait "$pid"
        status=$?
    fi
    grep -v '^test .* ok$' "$OUT/tests.log" | tail -60
    if [[ $status == 124 ]]; then
        echo "tests stopped after ${TESTS_TIMEOUT:-300} s; threads by what they wait in" \
            "(stall.txt has each one's kernel stack):"
        grep -E '^  task' "$OUT/stall.txt" | awk '{print $4, $5}' | sort | uniq -c | sort -rn | head -20
        echo "not reported:"
        ./.device/gpurt-tests --list 2>/dev/null | sed -n 's/: test$//p' | sort >/tmp/all-tests
        grep -oE '^test [^ ]+' "$OUT/tests.log" | cut -d' ' -f2 | sort | comm -23 /tmp/all-tests - | head -40
    fi
    [[ -d target/gpu-vs-cpu ]] && tar -C target -czf "$OUT/gpu-vs-cpu.tar.gz" gpu-vs-cpu
fi

if [[ $what == *loss* ]]; then
    # Whether a device destroyed with work in flight stalls other processes' devices on
    # the same GPU (docs/gpu.md, "A device destroyed with work in flight"): fifteen
    # renders of balls-4 start, then a render that destroys its device once its first
    # band is in; each is given 60 s.
    echo "== loss"
    tmp=$(mktemp -d)
    for i in $(seq 15); do
        timeout 60 ./.device/gpurt "${scenes[0]}" --backend gpu -o "$tmp/busy-$i.png" \
            --width "${hd[0]}" --height "${hd[1]}" --spp 256 >"$tmp/busy-$i.log" 2>&1 &
    done
    sleep 2
    SECONDS=0
    GPURT_FAULT=lose-device GPURT_BAND_BYTES=4194304 timeout 60 ./.device/gpurt \
        "$manifest/scenes/spheres.nff" --backend gpu -o "$tmp/lost.png" --width 512 \
        --height 2048 --spp 4 2>&1 | tail -1
    echo "lost: exit ${PIPESTATUS[0]} after $SECONDS s"
    wait
    finished=0
    for i in $(seq 15); do
        if [[ -s $tmp/busy-$i.png ]]; then
            finished=$((finished + 1))
        else
            echo "busy $i: no image: $(tail -1 "$tmp/busy-$i.log")"
        fi
    done
    echo "busy renders finished: $finished of 15"
    echo "lost in the suite, beside the GPU tests:"
    # Waits end after 30 s (GPURT_WAIT_LIMIT): a stall shows as tests failing with "did
    # not finish", which names them, before the 120 s limit.
    GPURT_WAIT_LIMIT=30 timeout 120 ./.device/gpurt-tests \
        --test-threads "$(nproc)" gpu:: cli::errors::a_device_lost >"$OUT/loss-tests.log" 2>&1
    echo "exit $? (124: stalled)"
    grep -E '^test result|running for over|did not finish' "$OUT/loss-tests.log" | head -20
    rm -rf "$tmp"
fi

if [[ $what == *huge* ]]; then
    echo "== huge"
    tmp=$(mktemp -d)
    for scene in "mount 10" "mount 11" "balls 7"; do
        read -r model size <<<"$scene"
        ./.device/spd "$model" "$size" >"$tmp/$model-$size.nff"
        for backend in gpu cpu; do
            echo "-- $model-$size $backend"
            /usr/bin/time -f "wall        %e s" ./.device/gpurt "$tmp/$model-$size.nff" \
                --backend "$backend" --width 3840 --height 2160 -o "$tmp/out.png" --stats 2>&1 |
                grep -E '^(scene|parse|build|shader|gpu |cpu |total|peak|wall|gpurt)'
        done
        rm -f "$tmp/$model-$size.nff"
    done 2>&1 | tee "$OUT/huge.log"
    rm -rf "$tmp"
fi
