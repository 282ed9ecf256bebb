#!/usr/bin/env bash
# Renders SCENE as N shards on a Slurm job array, then merges them into OUT:
#
#   deploy/slurm/submit.sh SCENE OUT N [render options...]
#
# SHARD_DIR (default: OUT's name with .shards) must be on storage every node sees, and
# GPURT the gpurt binary (default: gpurt on PATH). Prints the merge job's id.
set -euo pipefail
[ $# -ge 3 ] || { echo "usage: $0 SCENE OUT N [render options...]" >&2; exit 2; }
HERE=$(cd "$(dirname "$0")" && pwd)
SCENE=$(realpath "$1"); OUT=$(realpath -m "$2"); N=$3; shift 3
SHARD_DIR=$(realpath -m "${SHARD_DIR:-${OUT%.*}.shards}")
export GPURT="${GPURT:-gpurt}" SCENE OUT SHARD_DIR GPURT_ARGS="$*"
array=$(sbatch --parsable --export=ALL --array=0-$((N - 1)) "$HERE/render.sbatch")
sbatch --parsable --export=ALL --dependency="afterok:${array%%;*}" "$HERE/merge.sbatch"
