#!/usr/bin/env bash
# Builds what benches/gpu-device.sh runs and puts it, stripped, in .device/ (ignored by
# git): the release gpurt, the SPD generator (examples/spd.rs), the integration-test
# binary, the debug gpurt the CLI tests call, and a copy of ../shared/scenes. Also fetches the Vulkan loader packages into .gl/
# when missing (a machine without a Rust toolchain may lack them too). .device/ is made
# afresh: keep nothing else there (a script to run on the device belongs in benches/).
set -euo pipefail
cd "$(dirname "$0")/.."

cargo build --release --quiet --bin gpurt --example spd
cargo build --quiet
tests=$(cargo test --no-run --message-format=json 2>/dev/null |
    python3 -c 'import json,sys
for l in sys.stdin:
    m = json.loads(l)
    if m.get("reason") == "compiler-artifact" and m["target"]["kind"] == ["test"] and m["target"]["name"] == "gpurt":
        print(m["executable"])')
rm -rf .device
mkdir -p .device
strip -o .device/gpurt target/release/gpurt
strip -o .device/spd target/release/examples/spd
# The test process and the gpurt it starts keep their symbol tables (not their debug
# information): a stalled suite's threads are then named by function (`eu-stack`).
strip --strip-debug -o .device/gpurt-debug target/debug/gpurt
strip --strip-debug -o .device/gpurt-tests "$tests"
# Compressed: what travels to the device is limited in size.
tar -C .. -cJf .device/shared.tar.xz shared/scenes
pwd >.device/manifest-dir

if ! ls .gl/libvulkan1_*.deb >/dev/null 2>&1; then
    mkdir -p .gl /tmp/amd64/partial
    o='-oAPT::Architecture=amd64 -oAPT::Architectures=amd64 -oDir::State::Lists=/tmp/amd64'
    # shellcheck disable=SC2086
    apt-get $o update -qq
    # shellcheck disable=SC2086
    (cd .gl && apt-get $o download libvulkan1 libegl1 libglvnd0 libopengl0 libgl1 libglx0 libgles2)
fi
# eu-stack, for the stacks of a stalled suite's threads (benches/gpu-device.sh unpacks
# it apart from the system's libraries).
if ! ls .gl/elfutils/elfutils_*.deb >/dev/null 2>&1; then
    mkdir -p .gl/elfutils /tmp/amd64/partial
    o='-oAPT::Architecture=amd64 -oAPT::Architectures=amd64 -oDir::State::Lists=/tmp/amd64'
    # shellcheck disable=SC2086
    apt-get $o update -qq
    # shellcheck disable=SC2086
    (cd .gl/elfutils && apt-get $o download elfutils libdw1 libelf1 libdebuginfod1)
fi
du -sh .device .gl
