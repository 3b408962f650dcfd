#!/usr/bin/env bash
# The main job on a fresh machine: build the afb tool (only that target) of the release preset and drop the
# bundled figures onto a ground plane, with a readable report (speed, accuracy, stability, settle time). Extra
# arguments go to `afb drop`.
set -euo pipefail
cd "$(dirname "$0")/.."
cmake --preset release >/dev/null
# afb-double too only when asked for (`--precision double` execs it).
targets=(afb)
case " $* " in *double*) targets+=(afb-double) ;; esac
cmake --build --preset release --target "${targets[@]}"
afb=build/release/bin/afb
entities=$(sed -n 's/^entityDef[[:space:]]\{1,\}\([A-Za-z0-9_]*\).*/\1/p' def/*.def | sort | tr '\n' ' ')
echo
echo "== afb drop --base . --count 4 ${entities} $* =="
"$afb" drop --base . --count 4 ${entities} "$@"
