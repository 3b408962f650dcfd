#!/usr/bin/env bash
# Keeps workflow vocabulary out of the tracked files: comments, strings and docs speak of the behaviour itself and
# cite only documents that ship with the repository (docs/format.md, docs/architecture.md, ...).
#   cmake/check-words.sh    exits 1 listing `file:line: text` for every hit, else reports the files it read
# Flagged, case-insensitively: the word "session(s)", "issue" followed by a number or '#', "ticket", "af-format",
# "shared/docs"; and, case-sensitively, the upper-case file name "ARCHITECTURE.md". Binary files and this script
# are skipped; the test corpus (../shared/data) is not part of the repository and is not read.
set -euo pipefail

usage() { sed -n '2,7s/^# \{0,1\}//p' "${BASH_SOURCE[0]}"; }
case "${1:-}" in
  "") ;;
  -h|--help) usage; exit 0 ;;
  *) usage >&2; exit 2 ;;
esac

cd "$(dirname "${BASH_SOURCE[0]}")/.."
self="cmake/check-words.sh"

if ! git rev-parse --is-inside-work-tree >/dev/null 2>&1; then
  echo "check-words: not a git work tree (the check reads git ls-files)" >&2
  exit 2
fi

mapfile -d '' files < <(git ls-files -z -- . ":(exclude)$self")
if [ ${#files[@]} -eq 0 ]; then
  echo "check-words: no tracked files" >&2
  exit 2
fi

# POSIX ERE (git grep -E); a word boundary is any character that is not a letter.
insensitive='(^|[^[:alpha:]])sessions?([^[:alpha:]]|$)|issues?[[:space:]_-]*(#|[0-9])|ticket|af-format|shared/docs'
sensitive='ARCHITECTURE\.md'

hits="$( {
  git grep -I -n -i -E -e "$insensitive" -- . ":(exclude)$self" || true
  git grep -I -n -E -e "$sensitive" -- . ":(exclude)$self" || true
} | sort -t: -k1,1 -k2,2n -u)"

if [ -n "$hits" ]; then
  # git grep prints file:line:text; the text keeps any colons of its own.
  sed -E 's/^([^:]*):([0-9]+):/\1:\2: /' <<<"$hits"
  n="$(cut -d: -f1 <<<"$hits" | sort -u | wc -l)"
  echo "check-words: $(wc -l <<<"$hits") lines in $n files use workflow words or cite documents outside the repository" >&2
  exit 1
fi
echo "check-words: ${#files[@]} files clean"
