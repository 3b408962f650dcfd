#!/usr/bin/env bash
# Instructions inside stepSimulation with the explosion guard on and off (4 humanoids, 1 m, 300 steps, sleeping
# off; tests/sim/test_stress.cpp "explosion guard: cost run"). Needs valgrind. The count includes RagdollWorld::step's
# check before each frame only through stepSimulation's callers, so the guard's share is counted inside the step
# (per substep) and the pre-frame check is left out; both are a pass over the bodies.
#   cmake/stress-guard-cost.sh [TESTS-BINARY]     (default build/release/bin/afb_tests, else build/dev/bin/afb_tests)
set -euo pipefail
cd "$(dirname "$0")/.."
tests=${1:-build/release/bin/afb_tests}
[ -x "$tests" ] || tests=build/dev/bin/afb_tests
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for guard in off on; do
  AFB_GUARD=$guard valgrind --tool=callgrind --collect-atstart=no \
    --toggle-collect='btDiscreteDynamicsWorld::stepSimulation*' --callgrind-out-file="$work/cg.$guard" \
    "$tests" "explosion guard: cost run" >/dev/null 2>"$work/log.$guard"
  printf 'guard %-3s %14s instructions\n' "$guard" "$(sed -n 's/^summary: *\([0-9]*\).*/\1/p' "$work/cg.$guard")"
done
