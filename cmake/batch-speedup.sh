#!/usr/bin/env bash
# GNU parallel's speedup on a sharded chart (docs/cluster.md, "Expected scaling"): the chart of 48 runs (humanoid,
# 6 instances, 10 s at 60 Hz, sleeping off; fast, default, accurate; 1 and 10 m; 8 repeats) in one process on one
# thread, against the same chart planned, run as 16 shards under `parallel -j 2` and merged. Prints each one's wall
# time and CPU time (user + system, children included) and the load average around them: on a machine that other
# jobs share, the wall times say what the machine gave, the CPU times what the work cost. Run from the repository
# root (the content folder).
# Usage: cmake/batch-speedup.sh AFB WORK [ROUNDS]   (ROUNDS: one-process and sharded runs, alternated; default 1)
set -euo pipefail
exec 3>&1 # measure() reports here, whatever its command's output is redirected to
afb=$1 work=$2 rounds=${3:-1}
command -v parallel > /dev/null || {
  echo "GNU parallel is not installed (cmake/install-deps.sh)" >&2
  exit 1
}
rm -rf "$work"
mkdir -p "$work"
chart=(--base . humanoid --methods fast,default,accurate --heights 1,10 --repeats 8 --seconds 10 --count 6 --no-sleep)

# TAG COMMAND...: runs it; prints its wall and CPU time and appends "TAG CPU WALL" to $work/times.
measure() {
  local tag=$1
  shift
  /usr/bin/time -o "$work/time.txt" -f "%U %S %e" "$@"
  read -r user sys wall < "$work/time.txt"
  awk -v t="$tag" -v u="$user" -v s="$sys" -v w="$wall" 'BEGIN { printf "%-12s %7.2f s wall, %7.2f s CPU\n", t, w, u + s }' >&3
  echo "$tag $(awk -v u="$user" -v s="$sys" 'BEGIN { print u + s }') $wall" >> "$work/times"
}

# The sharded chart: plan, 16 shards two at a time, merge (one process tree, so that time counts all of it).
sharded() {
  rm -rf "$work/results" "$work/merged"
  "$afb" plan chart "${chart[@]}" --manifest "$work/runs.jsonl" 2> /dev/null
  seq 0 15 | parallel --will-cite -j 2 /usr/bin/time -o "$work/shard-{}.time" -f %U,%S \
    "$afb" run --manifest "$work/runs.jsonl" --shard {}/16 --out "$work/results" > /dev/null
  "$afb" merge "$work/results" --out "$work/merged" > /dev/null
}

echo "afb: $("$afb" --version | head -1); $(nproc) CPUs"
for r in $(seq "$rounds"); do
  echo "load before round $r: $(uptime | sed 's/.*load average: //')"
  measure one-process "$afb" chart "${chart[@]}" --threads 1 --out "$work/one" > /dev/null 2>&1
  export -f sharded
  export afb work
  measure sharded bash -c "chart=(${chart[*]}); sharded"
  echo "load after round $r: $(uptime | sed 's/.*load average: //')"
done
awk '$1 == "one-process" { oc += $2; ow += $3; n++ } $1 == "sharded" { sc += $2; sw += $3 }
  END { printf "sharded / one-process: wall %.2f, CPU %.2f\n", sw / ow, sc / oc; print oc / n > "'"$work"'/one-cpu" }' \
  "$work/times"
# On two free cores: the last round's shards by their CPU times, started in order on whichever core frees first
# (as parallel -j 2 starts them), against the one-process CPU time (a core of its own).
for k in $(seq 0 15); do awk -F, '{ print $1 + $2 }' "$work/shard-$k.time"; done |
  awk -v one="$(cat "$work/one-cpu")" '{ if (a <= b) a += $1; else b += $1; t += $1 }
    END { m = a > b ? a : b; printf "16 shards on 2 free cores: %.1f s (the busier core; %.1f s of shards in all) = %.2f x one core'"'"'s %.1f s\n", m, t, m / one, one }' 
