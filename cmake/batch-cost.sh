#!/usr/bin/env bash
# The cost of afb plan, run and merge at scale (docs/cluster.md, "Expected scaling"): a chart of 100 800 runs of
# 0 s each (humanoid; fast, default, accurate; 2 heights; 168 rates; 100 repeats) planned, run on THREADS threads
# and merged, each step's CPU time (user + system, children included: gnuplot), wall time and peak memory as
# /usr/bin/time measures them. Run from the repository root (the content folder). Runs of 0 s have no points for
# the front: gnuplot's complaints about it go to WORK/merge.err.
# Usage: cmake/batch-cost.sh AFB WORK [THREADS]    (WORK: a scratch folder; about 1 GB is written there)
#        AFB_COST_MERGE_ONLY=1 cmake/batch-cost.sh AFB WORK    (the manifest and results of a previous call merged)
set -euo pipefail
exec 3>&1 # measure() reports here, whatever its command's output is redirected to
afb=$1 work=$2 threads=${3:-2}
mkdir -p "$work"
plan=(chart --base . humanoid --methods fast,default,accurate --heights 1,10 --hz "$(seq -s, 60 227)" --repeats 100
      --seconds 0)

# LABEL COMMAND...: runs it and prints "LABEL: CPU s (user + sys), wall s, peak MB".
measure() {
  local label=$1
  shift
  /usr/bin/time -o "$work/time.txt" -f "%U %S %e %M" "$@"
  read -r user sys wall kb < "$work/time.txt"
  awk -v l="$label" -v u="$user" -v s="$sys" -v w="$wall" -v k="$kb" \
    'BEGIN { printf "%-40s %6.2f s CPU (%.2f user + %.2f sys), %6.2f s wall, %5.0f MB peak\n", l, u + s, u, s, w, k / 1024 }' >&3
}

echo "afb: $("$afb" --version | head -1); load: $(uptime | sed 's/.*load/load/')"
measure "plan to /dev/null" "$afb" plan "${plan[@]}" --manifest - > /dev/null 2>&1
if [ -z "${AFB_COST_MERGE_ONLY:-}" ]; then # set: plan, run and results kept from a previous call
  rm -rf "$work"
  mkdir -p "$work"
  measure "plan to disk" "$afb" plan "${plan[@]}" --manifest "$work/runs.jsonl" 2> /dev/null
  measure "run ($threads threads)" "$afb" run --manifest "$work/runs.jsonl" --shard 0/1 --threads "$threads" \
    --out "$work/results" > /dev/null
fi
echo "manifest: $(grep -c . "$work/runs.jsonl") lines, $(du -m "$work/runs.jsonl" | cut -f1) MB"
echo "results: $(du -sm "$work/results" | cut -f1) MB on disk, $(wc -c < "$work/results/run-000000.json") bytes each"
rm -rf "$work/merged" "$work/merged-manifest"
measure "merge" "$afb" merge "$work/results" --out "$work/merged" > /dev/null 2> "$work/merge.err"
if "$afb" merge --help | grep -q "checked against its line"; then
  measure "merge --manifest (every line's hash)" "$afb" merge "$work/results" --manifest "$work/runs.jsonl" \
    --out "$work/merged-manifest" > /dev/null 2> "$work/merge.err"
fi
echo "load: $(uptime | sed 's/.*load/load/')"
