#!/usr/bin/env bash
# Runs every check CI runs, from a fresh Debian 12 machine (as root) or a developer's:
#   1. installs the Debian packages (scripts/install-deps.sh)
#   2. clang-format check                  (scripts/check-format.sh)
#   3. Release build with -Werror           -> build/
#   4. clang-tidy over that build           (scripts/run-clang-tidy.sh)
#   5. ASan+UBSan build and its tests       -> build-asan/ (libraries, Python module, their
#                                             tests; no tool, examples or benchmarks)
#   6. TSan build of the store tests (pager, patch cache: the concurrent code) -> build-tsan/
#   7. the Release tests, last, so the output ends with ctest's summary
#
#   bash scripts/test-all.sh
#
# Environment (all optional): BUILD_DIR (default build), ASAN_BUILD_DIR (default
# build-asan), REGOLITH_CMAKE_ARGS (extra arguments for both configure steps, split on
# spaces). Real-data fixtures come from ../shared/fixtures/dem unless REGOLITH_FIXTURES_DIR
# says otherwise.
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"

build_dir=${BUILD_DIR:-build}
asan_dir=${ASAN_BUILD_DIR:-build-asan}
tsan_dir=${TSAN_BUILD_DIR:-build-tsan}
read -r -a extra_args <<<"${REGOLITH_CMAKE_ARGS:-}"
jobs=2
start=$SECONDS

section() { printf '\n==== %s [%ds]\n' "$*" $((SECONDS - start)); }

section "Dependencies (scripts/install-deps.sh)"
bash scripts/install-deps.sh

section "Format (scripts/check-format.sh)"
bash scripts/check-format.sh

# Every option is spelled out, so a build folder configured earlier by hand (tests off,
# sanitizers on, ...) cannot quietly change what runs.
section "Release build with -Werror ($build_dir)"
cmake -S . -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE=Release -DREGOLITH_WERROR=ON \
  -DREGOLITH_SANITIZE= -DREGOLITH_BUILD_TESTS=ON -DREGOLITH_BUILD_TOOLS=ON \
  -DREGOLITH_BUILD_BENCH=ON "${extra_args[@]}"
cmake --build "$build_dir" -j"$jobs"

section "clang-tidy (scripts/run-clang-tidy.sh $build_dir)"
bash scripts/run-clang-tidy.sh "$build_dir"

# Debug for the clearest reports. -Werror stays with the Release build: GCC's sanitizer
# instrumentation can raise false -Wmaybe-uninitialized / -Wstringop-* warnings.
# The sanitized build covers the libraries and the Python module (their own suites); the
# command-line tool and the examples, thin front ends over the same libraries, are built
# and tested in the Release build only: under ASan their builds and end-to-end runs took
# about 3 of CI's 29 minutes (2026-12-01: some 190 s of compiling and 160 s of tests, on 2
# cores) for code the library suites already run.
section "ASan+UBSan build and tests ($asan_dir)"
# -g1 (line tables only): reports keep their file:line, and the build is a tenth faster
# than with full -g.
cmake -S . -B "$asan_dir" -G Ninja -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_FLAGS_DEBUG=-g1 \
  -DCMAKE_C_FLAGS_DEBUG=-g1 -DREGOLITH_WERROR=OFF -DREGOLITH_SANITIZE=address,undefined \
  -DREGOLITH_BUILD_TESTS=ON -DREGOLITH_BUILD_TOOLS=OFF -DREGOLITH_BUILD_EXAMPLES=OFF -DREGOLITH_BUILD_BENCH=OFF "${extra_args[@]}"
cmake --build "$asan_dir" -j"$jobs"
ASAN_OPTIONS=halt_on_error=1:print_stacktrace=1:detect_leaks=1 \
UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 \
  ctest --test-dir "$asan_dir" --output-on-failure --no-tests=error -j"$jobs"

# ThreadSanitizer on the concurrent code: the store tests (pager, cache, lock-free block
# table, prefetcher, threaded writer and import). tests/tsan.supp silences one lock-order
# report inside GDAL's driver registration.
section "TSan build and store tests ($tsan_dir)"
cmake -S . -B "$tsan_dir" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DREGOLITH_WERROR=OFF \
  -DREGOLITH_SANITIZE=thread -DREGOLITH_BUILD_TESTS=ON -DREGOLITH_BUILD_TOOLS=OFF \
  -DREGOLITH_BUILD_BENCH=OFF "${extra_args[@]}"
cmake --build "$tsan_dir" -j"$jobs" --target store_tests
# Two shards of the suite side by side (gtest sharding: every test runs in exactly one), one
# per core; each shard's output is printed whole when it ends.
tsan_pids=()
for ((shard = 0; shard < jobs; ++shard)); do
  TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1:suppressions=$root/tests/tsan.supp" \
  GTEST_TOTAL_SHARDS=$jobs GTEST_SHARD_INDEX=$shard \
    "$tsan_dir/tests/store/store_tests" --gtest_brief=1 >"$tsan_dir/shard$shard.log" 2>&1 &
  tsan_pids+=($!)
done
tsan_status=0
for ((shard = 0; shard < jobs; ++shard)); do
  wait "${tsan_pids[shard]}" || tsan_status=1
  echo "-- TSan shard $shard of $jobs"
  cat "$tsan_dir/shard$shard.log"
done
if ((tsan_status != 0)); then
  echo "test-all: a TSan shard of store_tests failed (its output is above)" >&2
  exit 1
fi

section "Release tests ($build_dir)"
ctest --test-dir "$build_dir" --output-on-failure --no-tests=error -j"$jobs"
