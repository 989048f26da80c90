#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Installs what is missing (Debian packages, apt-get), builds ÜberSim, and runs the default world.
#   ./setup.sh                 install + build + run models/worlds/div-b.yaml in real time (Ctrl-C stops)
#   ./setup.sh --no-run        install + build only
#   ./setup.sh --install-only  install only
#   ./setup.sh --sanitize      install + build the sanitizer build: clang, AddressSanitizer,
#                              UBSan and the fuzz targets, in build-asan (docs/reliability.md)
# Environment: BUILD_DIR (default build), SANITIZE_BUILD_DIR (default build-asan),
# BUILD_TYPE (default RelWithDebInfo), JOBS (default nproc).
set -euo pipefail
cd "$(dirname "$0")"

# Everything the build, the tests and the tools need, from Debian only.
PACKAGES=(
  g++ cmake ninja-build pkg-config git
  libode-dev libeigen3-dev liburdfdom-dev libtinyxml-dev libconsole-bridge-dev libassimp-dev
  libboost-dev libboost-program-options-dev zlib1g-dev
  libyaml-cpp-dev rapidjson-dev
  libprotobuf-dev protobuf-compiler
  libgtest-dev libgmock-dev libbenchmark-dev
  python3-protobuf python3-yaml python3-dev pybind11-dev python3-numpy python3-pytest
  python3-distributed python3-venv python3-pip python3-setuptools python3-wheel
  iproute2
)
# The viewer's end-to-end test drives a real browser: Debian's Chromium through its chromedriver
# and Selenium. Installed after the rest and not fatal: without them only that test is skipped.
BROWSER_PACKAGES=(chromium chromium-driver python3-selenium fonts-liberation)
# The sanitizer build only: clang with its sanitizer and libFuzzer runtimes, and llvm-symbolizer,
# which turns the addresses in a report into files and lines.
SANITIZER_PACKAGES=(clang libclang-rt-dev llvm)

# install_missing PACKAGE...: apt-get installs those not installed yet.
install_missing() {
  local missing=()
  for p in "$@"; do
    if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
      missing+=("$p")
    fi
  done
  if [ ${#missing[@]} -eq 0 ]; then
    return 0
  fi
  echo "setup: installing ${missing[*]}"
  local sudo=""
  if [ "$(id -u)" -ne 0 ]; then
    command -v sudo >/dev/null || { echo "setup: need root (or sudo) to apt-get install ${missing[*]}" >&2; exit 1; }
    sudo="sudo"
  fi
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
}

# build DIR [CMAKE_ARG...]: configures DIR the first time (with the arguments), then builds it.
build() {
  local dir="$1"
  shift
  local jobs="${JOBS:-$(nproc)}"
  if [ ! -f "$dir/build.ninja" ]; then
    cmake -S . -B "$dir" -G Ninja -DCMAKE_BUILD_TYPE="${BUILD_TYPE:-RelWithDebInfo}" "$@" >/dev/null
  fi
  cmake --build "$dir" -j "$jobs"
}

mode="${1:-run}"
install_missing "${PACKAGES[@]}"
if ! (install_missing "${BROWSER_PACKAGES[@]}"); then
  echo "setup: could not install ${BROWSER_PACKAGES[*]}; the viewer's browser test will be skipped" >&2
fi
[ "$mode" = "--install-only" ] && exit 0
if [ "$mode" = "--sanitize" ]; then
  install_missing "${SANITIZER_PACKAGES[@]}"
  build "${SANITIZE_BUILD_DIR:-build-asan}" -DCMAKE_CXX_COMPILER=clang++ -DUBERSIM_SANITIZE=ON -DUBERSIM_FUZZ=ON
  exit 0
fi
build "${BUILD_DIR:-build}"
[ "$mode" = "--no-run" ] && exit 0
exec "${BUILD_DIR:-build}/bin/ubersim" run
