#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Installs what is missing, builds, and runs the whole test suite (ctest).
#   ./test.sh               everything
#   ./test.sh -R collision  only tests matching a pattern (arguments go to ctest)
set -euo pipefail
cd "$(dirname "$0")"
./setup.sh --no-run
dir="${BUILD_DIR:-build}"
ctest --test-dir "$dir" -j "${JOBS:-$(nproc)}" --output-on-failure --timeout 1200 "$@"
