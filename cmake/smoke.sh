#!/usr/bin/env bash
# The smoke matrix: every afb command x every preset x the options that change code paths, in short runs on the
# bundled figures. Each run must end with exit 0, 1 or 2 (a result, a reported error, or a refused command line such
# as --lod with a backend that has none; docs/cli.md), never by a signal or with another code. Prints one line per run that did not, and a summary line; exits 1 when any run did not.
#
#   cmake/smoke.sh [AFB] [WORK_DIR]     AFB defaults to build/dev/bin/afb; WORK_DIR to a temporary folder
#
# Runs from the repository root (the bundled content: af/, def/, models/).
set -uo pipefail
cd "$(dirname "$0")/.."
afb="${1:-build/dev/bin/afb}"
work="${2:-$(mktemp -d)}"
mkdir -p "$work"
[ -x "$afb" ] || { echo "smoke: no afb at $afb" >&2; exit 2; }

presets=(fast iterative default exact accurate legacy multibody raw)
runs=0
bad=0
start=$SECONDS

# run LABEL COMMAND...: one run of the matrix.
run() {
  local label="$1"
  shift
  runs=$((runs + 1))
  "$@" >"$work/out.txt" 2>&1
  local rc=$?
  if [ "$rc" -gt 2 ]; then
    bad=$((bad + 1))
    echo "smoke: FAILED (exit $rc) $label: $*"
    tail -n 5 "$work/out.txt" | sed 's/^/    /'
  fi
}

# Commands that do not simulate.
run parse "$afb" parse af/*.af def/*.def
run fmt "$afb" fmt --check af/humanoid.af
run resolve "$afb" resolve --json --base . humanoid
run inspect "$afb" inspect --json --base . buggy
run draw-png "$afb" draw --base . humanoid --out "$work/humanoid.png"
run draw-svg "$afb" draw --base . lamp --out "$work/lamp.svg"
run draw-names "$afb" draw --base . buggy --show bodies,joints,limits,names --out "$work/buggy-names.png"
run golden-reports "$afb" golden compare --junit "$work/goldens.xml" --report "$work/golden-report" tests/golden/*.json
run gen "$afb" gen models/md5/humanoid/humanoid.md5mesh --out "$work/gen" --json
run methods "$afb" methods
run methods-json "$afb" methods raw --json

# afb drop: every preset with each option that takes another path through the code.
drop_options=(
  ""
  "--lod 6"
  "--precision double"
  "--hz 15"
  "--hz 240"
  "--threads 2 --worlds 4 --count 4"
  "--gltf $work/drop.glb"
  "--stop-at-rest --seconds 3"
  "--doom-gravity"
  "--merge-fixed on"
  "--no-sleep --count 3 --seed 5"
)
for preset in "${presets[@]}"; do
  for options in "${drop_options[@]}"; do
    seconds="--seconds 0.5"
    [[ "$options" == *--seconds* ]] && seconds=""
    entities="humanoid chain"
    [[ "$options" == *--gltf* ]] && entities="humanoid" # a replay records one entity
    # shellcheck disable=SC2086  # the options and entities are words
    run "drop $preset $options" "$afb" drop --base . $entities --method "$preset" $seconds $options
  done
  # Sunk ragdolls: figures that spawn at rest beside an awake one, long enough to freeze and sink.
  run "drop $preset sunk" "$afb" drop --base . humanoid_sleeping humanoid --count 2 --method "$preset" --seconds 2
  run "golden $preset" "$afb" golden record --base . chain --seconds 0.5 --method "$preset" \
    --out "$work/golden-$preset.json"
  [ -f "$work/golden-$preset.json" ] && run "golden compare $preset" "$afb" golden compare "$work/golden-$preset.json"
  run "draw $preset" "$afb" draw --base . chain --out "$work/chain-$preset.png"
  run "stress $preset" "$afb" stress --base . --methods "$preset" --scenarios tiny-bodies --yaws 1 \
    --out "$work/stress-$preset"
done
run "chart" "$afb" chart --base . chain --methods "$(IFS=,; echo "${presets[*]}")" --heights 1 --seconds 0.5 \
  --threads 2 --out "$work/chart"
run "stress threads" "$afb" stress --base . --methods default,multibody --scenarios rope-30,tiny-bodies --yaws 2 \
  --threads 2 --out "$work/stress-threads"

echo "smoke: $((runs - bad)) passed, $bad failed ($runs runs in $((SECONDS - start)) s)"
[ "$bad" -eq 0 ]
