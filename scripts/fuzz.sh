#!/usr/bin/env bash
# Builds (if needed) and runs each libFuzzer target of tests/fuzz for N seconds (FUZZ_PARALLEL
# at a time, by default one after the other), and reports per target: executions, executions
# per second, new corpus units, and the crashes, hangs, leaks and out-of-memory inputs found
# (docs/reliability.md, "Fuzzing").
#
#   bash scripts/fuzz.sh [seconds per target, default 60] [target ...]
#   bash scripts/fuzz.sh --seeds        # rewrites the seed corpus (tests/fuzz/corpus)
#
# Targets: fuzz_store, fuzz_import, fuzz_csv_points, fuzz_info_json (default: all four).
# Environment (all optional):
#   FUZZ_BUILD_DIR   build folder (default build-fuzz), configured with clang,
#                    -DREGOLITH_FUZZ=ON (ASan + UBSan + libFuzzer coverage)
#   FUZZ_RUNS        also stop a target after this many executions (e.g. 1000000)
#   FUZZ_NICE        niceness of the fuzz processes (default 10: the machine is shared)
#   FUZZ_TIMEOUT     seconds after which one input counts as a hang (default 20)
#   FUZZ_JOBS        build jobs (default 2)
#   FUZZ_PARALLEL    targets run at once (default 1)
# The committed seeds (tests/fuzz/corpus/<target>) are copied into
# <build>/fuzz/<target>/corpus, where the corpus grows from run to run; findings are written
# to <build>/fuzz/<target>/run-<UTC time>/ (crash-*, timeout-*, leak-*, oom-*; slow-unit-*, an input
# slower than 10 s, is counted apart and is not a finding). Reproduce one with
# `<build>/tests/fuzz/<target> <file>`. Exit status 1 if any target found anything.
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"
build=${FUZZ_BUILD_DIR:-build-fuzz}
all_targets=(fuzz_store fuzz_import fuzz_csv_points fuzz_info_json)

configure_and_build() {
  if [[ ! -f $build/build.ninja ]]; then
    local launcher=()
    if command -v ccache >/dev/null; then
      export CCACHE_BASEDIR=$root
      launcher=(-DCMAKE_C_COMPILER_LAUNCHER=ccache -DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
    fi
    # -O2 -g1: fast targets whose reports keep file:line.
    CC=clang CXX=clang++ cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
      "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O2 -g1" "-DCMAKE_C_FLAGS_RELWITHDEBINFO=-O2 -g1" \
      -DREGOLITH_FUZZ=ON -DREGOLITH_BUILD_TESTS=OFF -DREGOLITH_BUILD_BENCH=OFF \
      -DREGOLITH_BUILD_PYTHON=OFF -DREGOLITH_BUILD_EXAMPLES=OFF -DREGOLITH_BUILD_TOOLS=OFF \
      -DREGOLITH_UNITY_LIBRARIES=ON "${launcher[@]}" >/dev/null
  fi
  cmake --build "$build" -j"${FUZZ_JOBS:-2}" --target fuzz_targets
}

if [[ ${1:-} == --seeds ]]; then
  configure_and_build
  corpus=tests/fuzz/corpus
  # regression_* seeds are inputs of fixed findings: kept.
  find "$corpus/fuzz_store" "$corpus/fuzz_info_json" -type f ! -name 'regression_*' -delete \
    2>/dev/null || true
  "$build/tests/fuzz/make_store_seeds" tests/data/dem "$corpus/fuzz_store" "$corpus/fuzz_info_json"
  /usr/bin/python3 tests/fuzz/make_corpus.py tests/data/dem
  du -sh "$corpus"
  exit 0
fi

seconds=${1:-60}
shift || true
targets=("$@")
((${#targets[@]})) || targets=("${all_targets[@]}")
configure_and_build

# ASan: a 16 MiB quarantine (use after free is still caught among the recent frees) and no
# fill of new blocks make HDF5's thousands of small allocations per open 2.5 times faster.
export ASAN_OPTIONS=${ASAN_OPTIONS:-halt_on_error=1:detect_leaks=1:quarantine_size_mb=16:max_malloc_fill_size=0}
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$root/tests/fuzz/lsan.supp:print_suppressions=0}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-halt_on_error=1:print_stacktrace=1}
run_target() {
  local t=$1
  work=$build/fuzz/$t
  mkdir -p "$work/corpus"
  cp -n tests/fuzz/corpus/"$t"/* "$work/corpus/" 2>/dev/null || true
  found_dir=$work/run-$(date -u +%Y%m%dT%H%M%S)
  mkdir -p "$found_dir"
  args=(-max_total_time="$seconds" -timeout="${FUZZ_TIMEOUT:-20}" -rss_limit_mb=2560
    -print_final_stats=1 -artifact_prefix="$found_dir/" -close_fd_mask=3)
  [[ -n ${FUZZ_RUNS:-} ]] && args+=(-runs="$FUZZ_RUNS")
  log=$work/last-run.log
  echo "fuzz: $t for ${seconds} s${FUZZ_RUNS:+ or $FUZZ_RUNS runs} (log: $log)"
  rc=0
  nice -n "${FUZZ_NICE:-10}" "$build/tests/fuzz/$t" "${args[@]}" "$work/corpus" >"$log" 2>&1 || rc=$?
  runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)
  added=$(sed -n 's/^stat::new_units_added: *//p' "$log" | tail -1)
  count() { find "$found_dir" -maxdepth 1 -name "$1-*" | wc -l; }
  crashes=$(count crash) hangs=$(count timeout) leaks=$(count leak) ooms=$(count oom) slow=$(count slow-unit)
  found=$((crashes + hangs + leaks + ooms))
  # slow-unit-* files (an input slower than 10 s, not a finding) keep the folder.
  rmdir "$found_dir" 2>/dev/null || true
  if ((rc != 0 || found > 0)); then
    echo 1 >"$work/last-status"
    echo "fuzz: $t stopped with status $rc; the end of its log:"
    grep -E "ERROR|SUMMARY|Test unit written|deadly signal|uncaught|runtime error" "$log" | head -20
  fi
  printf '%s\n' "$(printf '%-16s %10s runs %8s exec/s %6s new units   crashes %s, hangs %s, leaks %s, ooms %s; slow units %s' \
    "$t" "${runs:-?}" "${rate:-?}" "${added:-?}" "$crashes" "$hangs" "$leaks" "$ooms" "$slow")" \
    >"$work/last-summary"
}
# FUZZ_PARALLEL targets run at once (default 1; CI runs as many as it has cores), each one
# libFuzzer process; their output lines may interleave, the summary below is in order.
parallel=${FUZZ_PARALLEL:-1}
pids=()
for t in "${targets[@]}"; do
  rm -f "$build/fuzz/$t/last-status" "$build/fuzz/$t/last-summary"
  run_target "$t" &
  pids+=($!)
  if ((${#pids[@]} >= parallel)); then
    wait "${pids[0]}" || true
    pids=("${pids[@]:1}")
  fi
done
for p in "${pids[@]}"; do wait "$p" || true; done
summary=()
status=0
for t in "${targets[@]}"; do
  [[ -f $build/fuzz/$t/last-status ]] && status=1
  summary+=("$(cat "$build/fuzz/$t/last-summary" 2>/dev/null || echo "$t: no summary (the run did not finish)")")
done
echo
echo "fuzz: ${seconds} s per target ($(nproc) cores, $(uname -m)); findings in $build/fuzz/<target>/run-*/"
printf '%s\n' "${summary[@]}"
exit $status
