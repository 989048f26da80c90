#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# Runs one libFuzzer target for a bounded time; fails (non-zero) on any crash, hang (an input
# taking over 10 s), leak, memory blow-up or sanitizer report. ctest calls it (tests/fuzz); it
# works by hand too (docs/reliability.md):
#   run_fuzzer.sh FUZZER SEED_CORPUS WORK_DIR [libFuzzer option...]
# UBERSIM_FUZZ_SECONDS: how long to fuzz (default 20). New inputs are kept in WORK_DIR/corpus,
# crash inputs in WORK_DIR/artifacts; the seed corpus is only read.
set -eu
if [ $# -lt 3 ]; then
  echo "usage: $0 FUZZER SEED_CORPUS WORK_DIR [libFuzzer option...]" >&2
  exit 2
fi
fuzzer=$1
seeds=$2
work=$3
shift 3
seconds=${UBERSIM_FUZZ_SECONDS:-20}
mkdir -p "$work/corpus" "$work/artifacts"
# libFuzzer stops by itself after -max_total_time; `timeout` only guards against a fuzzer that
# cannot stop (a hang outside an input, which -timeout does not see).
exec timeout --kill-after=30 $((seconds + 300)) "$fuzzer" \
  -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
  -artifact_prefix="$work/artifacts/" "$@" "$work/corpus" "$seeds"
