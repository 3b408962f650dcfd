#!/usr/bin/env bash
# The main job on a fresh machine: build the release preset and run afb on a bundled figure.
# Until `afb drop` exists this parses every bundled file and resolves the bundled `chain` entity.
set -euo pipefail
cd "$(dirname "$0")/.."
cmake --preset release >/dev/null
cmake --build --preset release
afb=build/release/bin/afb
echo
echo "== afb parse: every bundled .af, .def, .md5mesh and .md5anim =="
"$afb" parse --json af/*.af def/*.def $(find models -name '*.md5mesh' -o -name '*.md5anim' | sort)
echo
echo "== afb resolve --base . chain =="
"$afb" resolve --base . chain
