#!/usr/bin/env bash
# Builds examples/ as a separate project against an installed afbullet (find_package) and runs each program:
# on the bundled content (exit 0 required), with a misspelled entity name and with a missing content folder
# (exit 1 and an "error:" line required; a crash fails).
#   cmake/examples.sh PREFIX      an afbullet install prefix (cmake --install <build dir> --prefix PREFIX)
#   cmake/examples.sh BUILD_DIR   a built afbullet build tree (holds CMakeCache.txt): installed into a fresh
#                                 temporary prefix first
# The examples are built in a temporary folder (removed on exit) with Ninja when present, -j2.
set -euo pipefail

usage() { sed -n '2,8s/^# \{0,1\}//p' "${BASH_SOURCE[0]}"; }
case "${1:-}" in -h|--help) usage; exit 0 ;; esac
[ $# -eq 1 ] && [ -n "$1" ] || { usage >&2; exit 2; }
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
given="$(cd "$1" && pwd)"

tmp="$(mktemp -d "${TMPDIR:-/tmp}/afb-examples.XXXXXX")"
trap 'rm -rf "$tmp"' EXIT

if [ -f "$given/CMakeCache.txt" ]; then
  prefix="$tmp/prefix"
  echo "== cmake --install $given --prefix $prefix"
  cmake --install "$given" --prefix "$prefix" >"$tmp/install.log" || { cat "$tmp/install.log"; exit 1; }
else
  prefix="$given"
fi

generator=()
if command -v ninja >/dev/null 2>&1; then generator=(-G Ninja); fi
echo "== configure examples/ against $prefix"
cmake -S "$root/examples" -B "$tmp/build" "${generator[@]}" -DCMAKE_PREFIX_PATH="$prefix" \
  -DAFB_EXAMPLES_CONTENT_DIR="$root"
cmake --build "$tmp/build" -j2

failed=0
# expect RC PROGRAM ARGS...: runs the program, prints its output, checks its exit code (and "error:" when 1).
expect() {
  local want="$1" rc=0
  shift
  echo
  echo "== $(basename "$1") ${*:2}   (expect exit $want)"
  "$tmp/build/$1" "${@:2}" >"$tmp/out" 2>&1 || rc=$?
  cat "$tmp/out"
  if [ "$rc" -ne "$want" ]; then
    echo "FAILED: exit $rc, expected $want$([ "$rc" -gt 128 ] && echo " (signal $((rc - 128)))")"
    failed=1
  elif [ "$want" -eq 1 ] && ! grep -q '^error: ' "$tmp/out"; then
    echo "FAILED: no 'error: ' line"
    failed=1
  fi
}
for program in hello_ragdoll shoot_and_hit start_from_animation; do
  expect 0 "$program" "$root" humanoid
  expect 1 "$program" "$root" humanoidd
  expect 1 "$program" "$root/no-such-folder" humanoid
done
expect 1 start_from_animation "$root" humanoid no_such_anim

echo
if [ "$failed" -ne 0 ]; then
  echo "== examples: FAILED"
  exit 1
fi
echo "== examples: all passed"
