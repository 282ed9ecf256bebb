#!/usr/bin/env bash
# Builds the browser page into web/dist/ (index.html, app.js, gpurt_web.js, gpurt_web_bg.wasm)
# from a clean checkout: adds the wasm32-unknown-unknown target and installs
# wasm-bindgen-cli at the version Cargo.lock pins for wasm-bindgen (into
# target/wasm-tools/, inside the checkout) when they are missing. Serve the result with
#     python3 -m http.server -d web/dist
set -euo pipefail
cd "$(dirname "$0")/.."
# What each long step is doing, on stderr: the builds below are quiet and take minutes.
say() { echo "web/build.sh: $*" >&2; }

if ! rustup target list --installed | grep -qx wasm32-unknown-unknown; then
    say "adding the wasm32-unknown-unknown target"
    rustup target add wasm32-unknown-unknown
fi

# The CLI must match the wasm-bindgen crate the glue was built with, to the patch version.
version=$(awk '$0 == "name = \"wasm-bindgen\"" { getline; gsub(/"/, "", $3); print $3 }' Cargo.lock)
tools="$PWD/target/wasm-tools"
# Only its `wasm-bindgen` binary, and unoptimised: it rewrites one small module a build
# (a second unoptimised, 0.3 s optimised, the same output), and compiles in 80 s instead
# of 190 on two cores.
if ! "$tools/bin/wasm-bindgen" --version 2>/dev/null | grep -qx "wasm-bindgen $version"; then
    # Not linted: CI lints this workspace's crates through RUSTC_WORKSPACE_WRAPPER, and
    # the tool is not one of them.
    say "installing wasm-bindgen-cli $version into target/wasm-tools (about 1.5 minutes on two cores, once)"
    CARGO_PROFILE_RELEASE_OPT_LEVEL=0 \
        env -u RUSTC_WORKSPACE_WRAPPER -u CLIPPY_ARGS \
        cargo install --quiet wasm-bindgen-cli --version "=$version" --root "$tools" \
        --bin wasm-bindgen
fi

# No debug lines in the page's module: they would triple its size.
say "building the page's wasm module (about 3 minutes on two cores the first time, seconds after)"
CARGO_PROFILE_RELEASE_DEBUG=false \
    cargo build --quiet --release -p gpurt-web --target wasm32-unknown-unknown
rm -rf web/dist
mkdir -p web/dist
"$tools/bin/wasm-bindgen" --target web --no-typescript --out-dir web/dist --out-name gpurt_web \
    target/wasm32-unknown-unknown/release/gpurt_web.wasm
cp web/index.html web/app.js web/dist/
say "done: serve it with python3 -m http.server -d web/dist"
ls -l web/dist
