#!/usr/bin/env bash
# Regenerates the chart of docs/methods.md (models/pictures/chart-humanoid.png): the bundled humanoid under every preset,
# plain Bullet ("raw") and a few knob variations, dropped from 1 m and 10 m at 60 Hz, on the release build.
# The run's files (runs.csv, summary.md, front.svg, front.gp, front.dat) stay in build/chart/. Extra arguments go
# to `afb chart` (e.g. --repeats 9, or --precision double).
set -euo pipefail
cd "$(dirname "$0")/.."
cmake --preset release >/dev/null
cmake --build --preset release --target afb afb-double
methods=(
  raw raw:substeps=2 raw:substeps=4 raw:iterations=20 # plain Bullet, and its own two levers
  legacy fast balanced iterative default accurate     # the presets (docs/methods.md; exact is default)
  default:substeps=2 iterative:position-iterations=2  # a preset with more steps; Bullet's iterations, 2 sweeps
  multibody multibody:substeps=2                      # the reduced-coordinate backend (docs/methods.md)
)
out=build/chart
build/release/bin/afb chart --base . humanoid --methods "$(IFS=,; echo "${methods[*]}")" --heights 1,10 --hz 60 \
  --repeats 5 --count 4 --threads 2 --max-anchor-error 0.05 --max-limit-error 20 --out "$out" "$@"
cp "$out/front.png" models/pictures/chart-humanoid.png
echo "chart.sh: models/pictures/chart-humanoid.png updated (summary: $out/summary.md)"
