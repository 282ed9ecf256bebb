#!/usr/bin/env bash
# Renders the README's gallery (docs/gallery/list.txt) into docs/gallery/ with the CPU
# backend. tests/gpurt/gallery.rs renders the same list and fails when an image here no
# longer matches: it compares; only this script writes.
#
# Usage: docs/gallery/regenerate.sh    (needs ../shared beside the checkout)
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
cd "$ROOT"
cargo build --release --quiet
grep -v '^#' docs/gallery/list.txt | while read -r name scene args; do
    # shellcheck disable=SC2086
    target/release/gpurt "$scene" $args --backend cpu -o "docs/gallery/$name.png"
done
