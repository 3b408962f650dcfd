#!/usr/bin/env bash
# Golden poses in CI for a repository of Doom 3 content (af/, def/, models/ as in Doom's base/): the steps that
# github-goldens.yml (GitHub Actions) and gitlab-goldens.yml (GitLab CI) run, in this order.
#   goldens.sh install   the Debian packages and the afb tool, built from an afbullet checkout
#   goldens.sh record    a golden file for every entity in AFB_ENTITIES that has none yet
#   goldens.sh compare   re-run every golden: exit 1 when one fails; AFB_REPORT/junit.xml (JUnit XML) and
#                        AFB_REPORT/summary.md with a picture of each failing golden
# Environment (defaults in brackets):
#   AFBULLET_DIR   the afbullet checkout that install builds, e.g. a git submodule [afbullet]
#   AFB            the afb to run [$AFBULLET_DIR/build/release/bin/afb]
#   AFB_BASE       the content folder [.]
#   AFB_GOLDENS    the folder of golden files, committed with the content [goldens]
#   AFB_ENTITIES   the entities to record, separated by spaces [every entityDef of $AFB_BASE/def/*.def]
#   AFB_REPORT     the report folder [golden-report]
#   AFB_RECORD     extra options of afb golden record, e.g. "--height 2 --seconds 5" []
set -euo pipefail

afbullet_dir="${AFBULLET_DIR:-afbullet}"
afb="${AFB:-$afbullet_dir/build/release/bin/afb}"
base="${AFB_BASE:-.}"
goldens="${AFB_GOLDENS:-goldens}"
report="${AFB_REPORT:-golden-report}"

usage() { sed -n '2,16s/^# \{0,1\}//p' "${BASH_SOURCE[0]}"; }

install() {
  "$afbullet_dir/cmake/install-deps.sh"
  (cd "$afbullet_dir" && cmake --preset release >/dev/null && cmake --build --preset release --target afb)
  "$afb" --version
}

record() {
  local entities="${AFB_ENTITIES:-}"
  if [ -z "$entities" ]; then
    entities=$(sed -n 's/^entityDef[[:space:]]\{1,\}\([A-Za-z0-9_]*\).*/\1/p' "$base"/def/*.def | sort -u | tr '\n' ' ')
  fi
  mkdir -p "$goldens"
  local e
  for e in $entities; do
    if [ -f "$goldens/$e.json" ]; then
      echo "goldens: $goldens/$e.json exists"
    else
      # shellcheck disable=SC2086  # AFB_RECORD is a list of options
      "$afb" golden record --base "$base" "$e" --out "$goldens/$e.json" ${AFB_RECORD:-}
    fi
  done
}

compare() {
  mkdir -p "$report"
  shopt -s nullglob
  local files=("$goldens"/*.json)
  if [ ${#files[@]} -eq 0 ]; then
    echo "goldens: no golden files in $goldens (run: goldens.sh record)" >&2
    exit 1
  fi
  "$afb" golden compare --junit "$report/junit.xml" --report "$report" "${files[@]}"
}

case "${1:-}" in
  install) install ;;
  record) record ;;
  compare) compare ;;
  -h|--help) usage ;;
  *) usage >&2; exit 2 ;;
esac
