#!/usr/bin/env bash
# Installs every Debian package afbullet needs to build, test, fuzz and benchmark.
# Idempotent: does nothing but a dpkg check when everything is already present.
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config git
  clang-14 libclang-rt-14-dev            # libFuzzer targets (fuzz preset)
  clang-format-14                        # cmake/check-format.sh (CI's format check)
  libbullet-dev                          # float and -float64 builds of Bullet
  libeigen3-dev
  libassimp-dev
  catch2                                 # Catch2 v2 on Debian 12
  libcli11-dev
  nlohmann-json3-dev
  libbenchmark-dev
  gnuplot-nox
  libcairo2-dev fonts-dejavu-core        # afb draw: 2D drawing, PNG and SVG output, a font for its labels
  libexpat1-dev                          # tests: the SVG pictures parse as XML
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"
echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -q
$SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
