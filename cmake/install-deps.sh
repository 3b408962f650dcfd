#!/usr/bin/env bash
# Installs every Debian package afbullet needs to build, test, fuzz and benchmark, and the Khronos glTF validator
# (npm package gltf-validator) that the tests run on `afb drop --gltf` replays.
# Idempotent: does nothing but a dpkg and an npm check when everything is already present.
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config git
  clang-14 libclang-rt-14-dev            # libFuzzer targets (fuzz preset)
  clang-format-14                        # cmake/check-format.sh (CI's format check)
  libbullet-dev                          # float and -float64 builds of Bullet
  libeigen3-dev
  libassimp-dev                          # afb drop --gltf: glTF 2.0 export; afb gen: importing rigged meshes
  catch2                                 # Catch2 v2 on Debian 12
  libcli11-dev
  nlohmann-json3-dev
  libbenchmark-dev
  gnuplot-nox
  libcairo2-dev fonts-dejavu-core        # afb draw: 2D drawing, PNG and SVG output, a font for its labels
  libexpat1-dev                          # tests: the SVG pictures parse as XML
  libxml2-utils                          # tests: xmllint validates afb golden compare's JUnit XML
  doxygen                                # the API reference (docs preset)
  parallel                               # afb plan/run/merge: the GNU parallel recipe (tests/cli/batch.sh)
  slurm-wlm munge                        # afb plan/run/merge: the Slurm recipe on a single-node Slurm (tests/cli/slurm.sh)
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

# Node.js and npm for the glTF validator: Debian's packages unless a node with npm is already there (a NodeSource
# nodejs bundles npm and conflicts with Debian's npm package).
command -v npm >/dev/null 2>&1 || missing+=(nodejs npm)

SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
else
  echo "install-deps: installing ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -q
  $SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

# The Khronos glTF validator, a JS library (tests/cli/validate_gltf.js runs it), pinned.
validator_version="2.0.0-dev.3.10"
validator_json="$(npm root -g 2>/dev/null)/gltf-validator/package.json"
if [ -f "$validator_json" ] && grep -q "\"version\": *\"$validator_version\"" "$validator_json"; then
  echo "install-deps: gltf-validator $validator_version present"
else
  echo "install-deps: installing gltf-validator $validator_version (npm, global)"
  $SUDO npm install -g --no-audit --no-fund "gltf-validator@$validator_version"
fi
