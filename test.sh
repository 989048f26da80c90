#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Installs what is missing, builds, and runs the whole test suite (ctest).
#   ./test.sh               everything
#   ./test.sh -R collision  only tests matching a pattern (arguments go to ctest)
#   ./test.sh --sanitize    then the sanitizer pass: the same tests again, built with clang,
#                           AddressSanitizer and UBSan, plus each fuzz target for
#                           $UBERSIM_FUZZ_SECONDS (default 20), in build-asan. CI (CI=true)
#                           always runs it. docs/reliability.md.
set -euo pipefail
cd "$(dirname "$0")"
sanitize=false
if [ "${1:-}" = "--sanitize" ]; then
  sanitize=true
  shift
fi
[ "${CI:-}" = "true" ] && sanitize=true
./setup.sh --no-run
dir="${BUILD_DIR:-build}"
ctest --test-dir "$dir" -j "${JOBS:-$(nproc)}" --output-on-failure --timeout 1200 "$@"
if $sanitize; then
  ./setup.sh --sanitize
  ctest --test-dir "${SANITIZE_BUILD_DIR:-build-asan}" -j "${JOBS:-$(nproc)}" --output-on-failure --timeout 1200 "$@"
fi
