#!/usr/bin/env bash
# Instructions per awake body-step of methods, exact from run to run (callgrind counts instructions; the chart's
# CPU times move with the machine's load). Counts only inside btDiscreteDynamicsWorld::stepSimulation, i.e. what
# `afb chart` times, for the same drop afb drop runs. Needs valgrind (not installed by install-deps.sh).
#   cmake/callgrind-cost.sh [AFB] ENTITY METHOD... [-- DROP-OPTIONS]
#   cmake/callgrind-cost.sh humanoid raw legacy default -- --count 4 --steps 300 --no-sleep
# AFB defaults to build/release/bin/afb; methods are afb chart's specs (NAME[:KNOB=VALUE]...).
# AFB_BASE=DIR takes the entity from another content folder (default: the repository root).
# AFB_COMMAND=track runs afb track instead of afb drop (its options after --, e.g. --anim FILE --strength 0).
set -euo pipefail
cd "$(dirname "$0")/.."
afb=build/release/bin/afb
if [ -x "${1:-}" ]; then afb="$1"; shift; fi
entity="$1"; shift
methods=()
while [ $# -gt 0 ] && [ "$1" != "--" ]; do methods+=("$1"); shift; done
[ "${1:-}" = "--" ] && shift
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
printf '%-36s %14s %16s %12s\n' method instructions awake_body_steps per_step
for spec in "${methods[@]}"; do
  # NAME:knob=value:... -> --method NAME --knob value ...
  IFS=: read -r -a parts <<<"$spec"
  args=(--method "${parts[0]}")
  for kv in "${parts[@]:1}"; do args+=("--${kv%%=*}" "${kv#*=}"); done
  valgrind --tool=callgrind --collect-atstart=no --toggle-collect='btDiscreteDynamicsWorld::stepSimulation*' \
    --callgrind-out-file="$work/cg.out" "$afb" "${AFB_COMMAND:-drop}" --base "${AFB_BASE:-.}" "$entity" "${args[@]}" --csv "$work/run.csv" "$@" \
    >/dev/null 2>"$work/valgrind.log" || true # afb drop exits 1 when a figure explodes: still counted
  [ -s "$work/run.csv" ] || { cat "$work/valgrind.log" >&2; exit 1; }
  ir=$(sed -n 's/^summary: *\([0-9]*\).*/\1/p' "$work/cg.out")
  column=$(head -n 1 "$work/run.csv" | tr ',' '\n' | grep -n '^awake_body_steps$' | cut -d: -f1)
  steps=$(sed -n 2p "$work/run.csv" | cut -d, -f"$column")
  awk -v spec="$spec" -v ir="$ir" -v steps="$steps" \
    'BEGIN { printf "%-36s %14s %16s %12.0f\n", spec, ir, steps, (steps > 0 ? ir / steps : 0) }'
done
