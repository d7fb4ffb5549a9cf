#!/usr/bin/env bash
# Runs every check CI runs, from a fresh Debian 12 machine (as root) or a developer's:
#   1. installs the Debian packages (scripts/install-deps.sh)
#   2. clang-format check                  (scripts/check-format.sh)
#   3. Release build with -Werror           -> build/
#   4. clang-tidy over that build           (scripts/run-clang-tidy.sh)
#   5. ASan+UBSan build of the core (topo, store, rover, compose) and its tests -> build-asan/
#      (REGOLITH_FULL_CHECKS=1: everything, with every test)
#   6. TSan build of the store tests (pager, patch cache: the concurrent code) -> build-tsan/
#   7. a short fuzz run: each libFuzzer target of tests/fuzz for REGOLITH_FUZZ_SECONDS (default
#      30) s, clang + ASan + UBSan (scripts/fuzz.sh)  -> build-fuzz/
#   8. the Release tests, last, so the output ends with ctest's summary
#
#   bash scripts/test-all.sh
#
# Environment (all optional): BUILD_DIR (default build), ASAN_BUILD_DIR (default
# build-asan), TSAN_BUILD_DIR (default build-tsan), FUZZ_BUILD_DIR (default build-fuzz),
# REGOLITH_FUZZ_SECONDS (default 30 per fuzz target), REGOLITH_CMAKE_ARGS (extra arguments for
# every configure step, split on spaces), REGOLITH_FULL_CHECKS=1 (sanitize and test every
# module, and run clang-tidy's analyzer on every directory: longer than CI allows). Real-data fixtures come from
# tests/data/dem unless REGOLITH_FIXTURES_DIR says otherwise.
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"

build_dir=${BUILD_DIR:-build}
asan_dir=${ASAN_BUILD_DIR:-build-asan}
tsan_dir=${TSAN_BUILD_DIR:-build-tsan}
read -r -a extra_args <<<"${REGOLITH_CMAKE_ARGS:-}"
# ccache (installed by install-deps) keeps every object of a run, keyed by its preprocessed
# source and flags, with paths taken relative to this checkout (CCACHE_BASEDIR): a second run
# on the same machine, in any clone, recompiles only what changed. The PCH settings let it
# cache the command's CLI11-precompiled sources too. REGOLITH_CCACHE=0 turns it off.
if [[ ${REGOLITH_CCACHE:-1} == 1 ]] && command -v ccache >/dev/null; then
  export CCACHE_BASEDIR=$root
  export CCACHE_SLOPPINESS=pch_defines,time_macros,include_file_mtime,include_file_ctime
  extra_args+=(-DCMAKE_C_COMPILER_LAUNCHER=ccache -DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
fi
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
  -DREGOLITH_BUILD_BENCH=ON -DREGOLITH_UNITY_LIBRARIES=OFF -DREGOLITH_TEST_PCH=OFF \
  "${extra_args[@]}"
cmake --build "$build_dir" -j"$jobs"

section "clang-tidy (scripts/run-clang-tidy.sh $build_dir)"
bash scripts/run-clang-tidy.sh "$build_dir"

# Runs a GoogleTest executable as $jobs shards side by side (gtest sharding: every test runs
# in exactly one shard), one per core, with the given VAR=value environment; each shard's
# output is printed whole when it ends, and any failing shard fails the run.
#
# A sanitizer's report fails the run even where no test failed: a report in a child process
# (which the parent may survive) or in a thread whose test still passed. The one exception
# is the sandbox that reads old stores' texts in a child process (store/src/Hdf5.cpp,
# readInChild): HDF5 reading a damaged heap there is the memory error the child exists to
# contain. Its reports go to $exe.shardN.sandbox.<pid> (REGOLITH_SANDBOX_REPORTS), are
# counted here, and each must be an access by HDF5 itself.
sanitizer_report='^(WARNING: ThreadSanitizer|==[0-9]+==ERROR: (Address|Leak)Sanitizer|.*: runtime error: )'
run_shards() {
  local name=$1 exe=$2
  shift 2
  local pids=() status=0 shard report
  rm -f "$exe".shard*.sandbox.*
  for ((shard = 0; shard < jobs; ++shard)); do
    env "$@" REGOLITH_SANDBOX_REPORTS="$exe.shard$shard.sandbox" \
      GTEST_TOTAL_SHARDS="$jobs" GTEST_SHARD_INDEX="$shard" \
      "$exe" --gtest_brief=1 >"$exe.shard$shard.log" 2>&1 &
    pids+=($!)
  done
  for ((shard = 0; shard < jobs; ++shard)); do
    wait "${pids[shard]}" || status=1
    echo "-- $name: shard $shard of $jobs"
    cat "$exe.shard$shard.log"
    if grep -Eq "$sanitizer_report" "$exe.shard$shard.log"; then
      echo "test-all: $name shard $shard: a sanitizer reported an error (above)" >&2
      status=1
    fi
  done
  local contained=0
  for report in "$exe".shard*.sandbox.*; do
    [[ -e $report ]] || continue
    # Only the sandbox's children write there; what they may report is HDF5's own access
    # (an HDF5 frame among the report's first three), not an error in Regolith's code.
    if ! grep -Eq '^ +#[0-2] .*libhdf5' "$report"; then
      echo "test-all: $name: a sanitizer report in the sandbox, not inside HDF5 ($report):" >&2
      cat "$report" >&2
      status=1
    fi
    contained=$((contained + 1))
  done
  echo "-- $name: $contained sanitizer report(s) in the sandbox's child processes, HDF5 on" \
    "damaged heaps ($exe.shard*.sandbox.*)"
  if ((status != 0)); then
    echo "test-all: $name failed (its output is above)" >&2
    exit 1
  fi
}

# Sanitizers cover the core, where memory and threading errors hide: topo (queries, the
# lock-free block table and hazard records), store (pager, patch cache, prefetcher, HDF5
# reads and crash-safe writes, GDAL import) and rover. The GL renderer, the scene, the
# Python module, the command-line tool and the examples are built and tested in the Release
# build. That keeps CI within its 20 minutes: the full sanitized build and all its tests
# took 9.5 of CI's 28 minutes (2026-12-01, 2 cores). REGOLITH_FULL_CHECKS=1 sanitizes and
# tests everything (and runs clang-tidy's analyzer everywhere).
full=${REGOLITH_FULL_CHECKS:-0}
# The sanitizer and fuzz builds compile each library in unity batches
# (REGOLITH_UNITY_LIBRARIES: the headers a batch's files share are parsed once), and the
# sanitized tests with a precompiled header of their common headers (REGOLITH_TEST_PCH): they check
# what the code does when it runs. How each file compiles on its own is the Release build's
# (and clang-tidy's, over its compile database). Measured in docs/ci.md.
unity=(-DREGOLITH_UNITY_LIBRARIES=ON -DREGOLITH_TEST_PCH=ON)
# REGOLITH_TEST_WORK_SCALE (tests/support/WorkScale.hpp): under a sanitizer the longest
# store tests (the paged queries under eviction from several threads, the huge procedural
# planet) keep every thread, path and assertion over a quarter of their points; the Release
# run does all of them. Those tests took 250 of the TSan run's 430 and 210 of the ASan run's
# 390 test-seconds (2026-12-04, cold CI machine).
work_scale=REGOLITH_TEST_WORK_SCALE=0.25
asan_env=(ASAN_OPTIONS=halt_on_error=1:print_stacktrace=1:detect_leaks=1
  UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 "$work_scale")

# Debug for the clearest reports, with -g1 (line tables: reports keep their file:line, and
# the build is a tenth faster than with -g). -Werror stays with the Release build: GCC's
# sanitizer instrumentation can raise false -Wmaybe-uninitialized / -Wstringop-* warnings.
section "ASan+UBSan build and tests ($asan_dir)"
if [[ $full == 1 ]]; then
  cmake -S . -B "$asan_dir" -G Ninja -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_FLAGS_DEBUG=-g1 \
    -DCMAKE_C_FLAGS_DEBUG=-g1 -DREGOLITH_WERROR=OFF -DREGOLITH_SANITIZE=address,undefined \
    -DREGOLITH_BUILD_TESTS=ON -DREGOLITH_BUILD_TOOLS=ON -DREGOLITH_BUILD_EXAMPLES=ON \
    -DREGOLITH_BUILD_PYTHON=ON -DREGOLITH_BUILD_BENCH=OFF "${unity[@]}" "${extra_args[@]}"
  cmake --build "$asan_dir" -j"$jobs"
  env "${asan_env[@]}" ctest --test-dir "$asan_dir" --output-on-failure --no-tests=error -j"$jobs"
else
  cmake -S . -B "$asan_dir" -G Ninja -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_FLAGS_DEBUG=-g1 \
    -DCMAKE_C_FLAGS_DEBUG=-g1 -DREGOLITH_WERROR=OFF -DREGOLITH_SANITIZE=address,undefined \
    -DREGOLITH_BUILD_TESTS=ON -DREGOLITH_BUILD_TOOLS=OFF -DREGOLITH_BUILD_EXAMPLES=OFF \
    -DREGOLITH_BUILD_PYTHON=OFF -DREGOLITH_BUILD_BENCH=OFF "${unity[@]}" "${extra_args[@]}"
  cmake --build "$asan_dir" -j"$jobs" --target topo_tests store_tests rover_tests compose_tests
  run_shards "ASan+UBSan topo_tests" "$asan_dir/tests/topo_tests" "${asan_env[@]}"
  run_shards "ASan+UBSan store_tests" "$asan_dir/tests/store/store_tests" "${asan_env[@]}"
  run_shards "ASan+UBSan rover_tests" "$asan_dir/tests/rover/rover_tests" "${asan_env[@]}"
  run_shards "ASan+UBSan compose_tests" "$asan_dir/tests/compose/compose_tests" "${asan_env[@]}"
fi

# ThreadSanitizer on the concurrent code: the store tests (pager, cache, lock-free block
# table, prefetcher, threaded writer and import). tests/tsan.supp silences one lock-order
# report inside GDAL's driver registration.
section "TSan build and store tests ($tsan_dir)"
# -g1 here too: line tables are all TSan's reports need.
cmake -S . -B "$tsan_dir" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O2 -g1 -DNDEBUG" "-DCMAKE_C_FLAGS_RELWITHDEBINFO=-O2 -g1 -DNDEBUG" \
  -DREGOLITH_WERROR=OFF \
  -DREGOLITH_SANITIZE=thread -DREGOLITH_BUILD_TESTS=ON -DREGOLITH_BUILD_TOOLS=OFF \
  -DREGOLITH_BUILD_EXAMPLES=OFF -DREGOLITH_BUILD_PYTHON=OFF -DREGOLITH_BUILD_BENCH=OFF \
  "${unity[@]}" "${extra_args[@]}"
cmake --build "$tsan_dir" -j"$jobs" --target store_tests
run_shards "TSan store_tests" "$tsan_dir/tests/store/store_tests" "$work_scale" \
  "TSAN_OPTIONS=halt_on_error=1:second_deadlock_stack=1:suppressions=$root/tests/tsan.supp"

# The fuzz targets (docs/reliability.md, "Fuzzing"): store open and reads, raster import,
# the query's CSV points, info --json; each from the committed seeds plus what earlier runs on
# this machine added to build-fuzz/fuzz/<target>/corpus. Any crash, hang or leak fails CI,
# and its input stays in build-fuzz/fuzz/<target>/run-*/.
section "Fuzz targets, ${REGOLITH_FUZZ_SECONDS:-30} s each (scripts/fuzz.sh)"
FUZZ_BUILD_DIR=${FUZZ_BUILD_DIR:-build-fuzz} FUZZ_JOBS=$jobs FUZZ_PARALLEL=$jobs FUZZ_NICE=0 \
  bash scripts/fuzz.sh "${REGOLITH_FUZZ_SECONDS:-30}"

if [[ -n ${CCACHE_BASEDIR:-} ]]; then
  section "ccache"
  ccache --show-stats 2>/dev/null | grep -iE "hits|misses|cache size" || true
fi

section "Release tests ($build_dir)"
ctest --test-dir "$build_dir" --output-on-failure --no-tests=error -j"$jobs"
