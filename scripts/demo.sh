#!/usr/bin/env bash
# The README's first command: installs what is missing, builds, and runs the main job.
#
#   bash scripts/demo.sh [extra arguments for `regolith demo`, e.g. --cache-mb 1 --frames 48]
#
# The configure options match scripts/test-all.sh, so both share one build folder.
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"
build_dir=${BUILD_DIR:-build}

echo "==== Dependencies (scripts/install-deps.sh)"
bash scripts/install-deps.sh

echo "==== Build ($build_dir, Release)"
# ccache as in scripts/test-all.sh (REGOLITH_CCACHE=0 turns it off).
launcher=()
if [[ ${REGOLITH_CCACHE:-1} == 1 ]] && command -v ccache >/dev/null; then
  export CCACHE_BASEDIR=$root
  export CCACHE_SLOPPINESS=pch_defines,time_macros,include_file_mtime,include_file_ctime
  launcher=(-DCMAKE_C_COMPILER_LAUNCHER=ccache -DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
fi
cmake -S . -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE=Release -DREGOLITH_WERROR=ON \
  -DREGOLITH_SANITIZE= -DREGOLITH_BUILD_TESTS=ON -DREGOLITH_BUILD_TOOLS=ON \
  -DREGOLITH_BUILD_BENCH=ON "${launcher[@]}" >/dev/null
cmake --build "$build_dir" -j2 --target regolith

echo "==== Main job: $build_dir/tools/regolith demo $*"
exec "$build_dir/tools/regolith" demo "$@"
