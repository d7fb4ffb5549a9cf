#!/usr/bin/env bash
# The storm of issue 17 (docs/reliability.md "Storm"): 16 threads query a paged DEM and
# planet while a Prefetcher moves its focus, under a cache budget of 4 patches, for
# SECONDS seconds (default 60); every answer is compared bit for bit with the single-threaded
# one and a watcher thread samples the resident bytes against the budget. The short version
# (2 s) is the ctest test Storm.* of store_tests, under TSan too (scripts/test-all.sh).
#
# Usage: scripts/storm.sh [BUILD_DIR (default build)] [SECONDS (default 60)]
set -euo pipefail
build=${1:-build}
seconds=${2:-60}
bin="$build/tests/store/store_tests"
[[ -x $bin ]] || { echo "storm.sh: $bin not found (ninja -C $build store_tests)" >&2; exit 1; }
REGOLITH_STORM_SECONDS=$seconds exec nice -n 10 "$bin" --gtest_filter='Storm.*'
