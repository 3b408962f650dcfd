#!/usr/bin/env bash
# Submits a manifest written by `afb plan` as a Slurm job array and its merge as a dependent job.
#   cmake/slurm/submit.sh MANIFEST RESULTS OUT [sbatch options...]
# One array task per manifest line, at most AFB_MAX_RUNNING at once (default 64); with AFB_SHARDS=N, N tasks of
# every N-th line each. AFB names the afb binary (default: afb on PATH). Extra arguments go to both sbatch calls
# (--partition, --time, --wait, ...). Prints the two job ids.
set -euo pipefail
if [ $# -lt 3 ]; then
  echo "usage: $0 MANIFEST RESULTS OUT [sbatch options...]" >&2
  exit 2
fi
manifest="$(realpath "$1")"
results="$(realpath -m "$2")"
out="$(realpath -m "$3")"
shift 3
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
runs=$(grep -c . "$manifest")
tasks="${AFB_SHARDS:-$runs}"
if [ "$tasks" -lt 1 ]; then
  echo "$0: $manifest has no runs" >&2
  exit 1
fi
mkdir -p "$results"
export AFB="${AFB:-$(command -v afb)}" AFB_MANIFEST="$manifest" AFB_RESULTS="$results" AFB_OUT="$out"
export AFB_SHARDS="${AFB_SHARDS:-}"
# The merge runs after every task ended, failed or not (afterany): it names what is missing.
array=$(sbatch --parsable --export=ALL --array="0-$((tasks - 1))%${AFB_MAX_RUNNING:-64}" "$@" "$here/afb-array.sbatch")
merge=$(sbatch --parsable --export=ALL --dependency="afterany:${array%%;*}" "$@" "$here/afb-merge.sbatch")
echo "array job ${array%%;*} ($tasks tasks of $runs runs), merge job ${merge%%;*} -> $out"
