#!/usr/bin/env bash
# Checks every tracked C++ file (*.h, *.cpp) against .clang-format; exits 1 listing the files that differ.
#   cmake/check-format.sh          check only (CI)
#   cmake/check-format.sh --fix    rewrite the files that differ in place
# Uses clang-format-14 when present (Debian 12's version; other versions format slightly differently),
# else clang-format. Environment: CLANG_FORMAT overrides the binary.
set -euo pipefail

usage() { sed -n '2,6s/^# \{0,1\}//p' "${BASH_SOURCE[0]}"; }

fix=0
case "${1:-}" in
  "") ;;
  --fix) fix=1 ;;
  -h|--help) usage; exit 0 ;;
  *) usage >&2; exit 2 ;;
esac
[ $# -le 1 ] || { usage >&2; exit 2; }

cd "$(dirname "${BASH_SOURCE[0]}")/.."

if [ -n "${CLANG_FORMAT:-}" ]; then
  cf="$CLANG_FORMAT"
elif command -v clang-format-14 >/dev/null 2>&1; then
  cf=clang-format-14
elif command -v clang-format >/dev/null 2>&1; then
  cf=clang-format
else
  echo "check-format: clang-format not found (Debian: apt-get install clang-format-14, or run cmake/install-deps.sh)" >&2
  exit 2
fi
version="$("$cf" --version)"
case "$version" in
  *"version 14."*) ;;
  *) echo "check-format: warning: $version is not clang-format 14; its output may differ from CI's" >&2 ;;
esac

if git rev-parse --is-inside-work-tree >/dev/null 2>&1; then
  mapfile -d '' files < <(git ls-files -z -- '*.h' '*.cpp')
else  # an exported tree without .git: the same sources, build folders left out
  mapfile -d '' files < <(find . -path './build*' -prune -o -path './.git' -prune -o \
                            -type f \( -name '*.h' -o -name '*.cpp' \) -printf '%P\0' | sort -z)
fi
if [ ${#files[@]} -eq 0 ]; then
  echo "check-format: no tracked C++ files" >&2
  exit 2
fi

# A broken .clang-format would otherwise show up as "every file differs".
if ! err="$("$cf" --style=file --dump-config "${files[0]}" 2>&1 >/dev/null)" || [ -n "$err" ]; then
  echo "check-format: $cf cannot use .clang-format:" >&2
  echo "$err" >&2
  exit 2
fi

differ=()
for f in "${files[@]}"; do
  "$cf" --style=file --dry-run --Werror "$f" >/dev/null 2>&1 || differ+=("$f")
done

if [ ${#differ[@]} -eq 0 ]; then
  echo "check-format: all ${#files[@]} files formatted ($version)"
  exit 0
fi

if [ "$fix" -eq 1 ]; then
  "$cf" --style=file -i "${differ[@]}"
  printf '  formatted %s\n' "${differ[@]}"
  echo "check-format: reformatted ${#differ[@]} of ${#files[@]} files"
  exit 0
fi

printf '  %s\n' "${differ[@]}"
echo "check-format: ${#differ[@]} of ${#files[@]} files differ from .clang-format; run cmake/check-format.sh --fix" >&2
exit 1
