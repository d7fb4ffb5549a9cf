#!/usr/bin/env bash
# Runs clang-tidy (version 14, checks from .clang-tidy) over Regolith's library and tool
# sources, two files at a time, and fails on any finding.
#
#   scripts/run-clang-tidy.sh [--record] [BUILD_DIR]     (default: build/ in the repository)
#
# --record also writes .ci/tidy-clean.txt after a clean run (see "Results cache" below).
#
# BUILD_DIR must hold compile_commands.json (every Regolith configure writes one). Sources
# that exist but are not in it (a module switched off in that build) are skipped with a note.
# CLANG_TIDY overrides the binary (default: clang-tidy); JOBS the parallelism (default: 2);
# REGOLITH_FULL_CHECKS=1 runs the path-sensitive analyzer in clod/, scenegraph/ and tools/
# too (their .clang-tidy files leave it to topo/, store/ and rover/ to keep CI short).
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
record=0
if [[ ${1:-} == --record ]]; then
  record=1
  shift
fi
build_dir=${1:-$root/build}
[[ -d $build_dir ]] && build_dir=$(cd "$build_dir" && pwd)
clang_tidy=${CLANG_TIDY:-clang-tidy}
jobs=${JOBS:-2}

db="$build_dir/compile_commands.json"
if [[ ! -f $db ]]; then
  echo "run-clang-tidy: $db not found; configure that build first" >&2
  exit 2
fi
command -v "$clang_tidy" >/dev/null || { echo "run-clang-tidy: $clang_tidy not found" >&2; exit 2; }

# Library sources of every module that exists, plus the command-line tool.
shopt -s nullglob
candidates=("$root"/{core,topo,store,compose,gl,clod,render,farfield,scene,scenegraph,demo,rover}/src/*.cpp "$root"/tools/*.cpp "$root"/tools/src/*.cpp "$root"/tools/viewer/*.cpp)
shopt -u nullglob

files=()
for f in "${candidates[@]}"; do
  if grep -qF "\"file\": \"$f\"" "$db"; then
    files+=("$f")
  else
    echo "run-clang-tidy: skipping ${f#"$root"/} (not in $db)"
  fi
done
if ((${#files[@]} == 0)); then
  echo "run-clang-tidy: no sources to check" >&2
  exit 2
fi

# clod/, scenegraph/ and tools/ switch the path-sensitive analyzer off in their own
# .clang-tidy (CI time); REGOLITH_FULL_CHECKS=1 turns it back on everywhere.
extra_checks=""
if [[ ${REGOLITH_FULL_CHECKS:-0} == 1 ]]; then
  extra_checks="--checks=clang-analyzer-core.*,clang-analyzer-cplusplus.*"
fi

echo "run-clang-tidy: $("$clang_tidy" --version | grep -o 'version [0-9.]*'), ${#files[@]} files, $jobs jobs"
log=$(mktemp)
tidy_db=$(mktemp -d)
trap 'rm -rf "$log" "$tidy_db"' EXIT
# The command's sources use a GCC precompiled header (tools/CMakeLists.txt), which clang
# cannot read: clang-tidy gets the same commands without it.
python3 "$root/scripts/tidy-key.py" strip-pch "$db" "$tidy_db"

# Results cache: a file whose key (scripts/tidy-key.py: its preprocessed text with comments,
# every .clang-tidy, the clang-tidy version and the extra checks) a clean run has recorded is
# not checked again. REGOLITH_TIDY_CACHE=0 (or REGOLITH_FULL_CHECKS=1) checks every file.
#
# Two places hold keys: this machine's cache folder, and .ci/tidy-clean.txt in the
# repository, the keys of the sources as they were at a clean run (written by
# `scripts/run-clang-tidy.sh --record`, committed with them). So a fresh machine, which CI
# always is, checks only the files that changed since that run: any change to a source, a
# header it includes (system headers too), a .clang-tidy or the clang-tidy version changes
# its key. Without this, a cold tidy of every file took 17 of CI's minutes on 2 cores.
#
# Each file has two keys over the same inputs: the fast one (`tidy-key.py deps-keys`: the
# files the compiler read for it, from the build's `ninja -t deps`, all files at once in
# seconds; none where the build holds no valid dependencies for the file's object) and the
# slow one (its preprocessed text, a second or two of the compiler per file), computed only
# when the fast one is not recorded. Before stop 38 the slow key was the only one: CI's tidy
# step took 2.7 minutes on a fresh machine with every key recorded. A file is clean if either
# key is recorded; --record writes the fast key where there is one.
cache_dir=""
: >"$tidy_db/keys.tsv"
if [[ ${REGOLITH_TIDY_CACHE:-1} == 1 && ${REGOLITH_FULL_CHECKS:-0} != 1 ]]; then
  cache_dir=${XDG_CACHE_HOME:-$HOME/.cache}/regolith-tidy
  mkdir -p "$cache_dir"
  python3 "$root/scripts/tidy-key.py" deps-keys "$db" "$root" "$extra_checks" "$build_dir" \
    >"$tidy_db/keys.tsv" || : >"$tidy_db/keys.tsv"
fi

# One clang-tidy per file; each prints its findings in one piece so parallel output does not
# interleave. xargs exits non-zero if any clang-tidy did (every kept check is an error).
status=0
printf '%s\0' "${files[@]}" |
  xargs -0 -n1 -P"$jobs" bash -c '
    # $0 clang-tidy, $1 compile database folder (with keys.tsv), $2 extra checks, $3 cache
    # folder (empty: no cache), $4 repository root, $5 the file (xargs appends it).
    # recorded KEY CACHE ROOT: a clean run recorded KEY here or in .ci/tidy-clean.txt.
    recorded() {
      [[ -n $1 ]] && { [[ -f $2/$1 ]] || grep -qxF "$1" "$3/.ci/tidy-clean.txt" 2>/dev/null; }
    }
    fast="" key=""
    if [[ -n $3 ]]; then
      fast=$(awk -F "\t" -v f="$5" "\$1 == f { print \$2 }" "$1/keys.tsv")
      recorded "$fast" "$3" "$4" && exit 0
      key=$(python3 "$4/scripts/tidy-key.py" key "$1/compile_commands.json" "$5" "$4" "$2" || true)
      if recorded "$key" "$3" "$4"; then
        [[ -n $fast ]] && touch "$3/$fast"
        exit 0
      fi
    fi
    out=$("$0" -p "$1" --quiet ${2:+"$2"} "$5" 2>&1) && rc=0 || rc=$?
    # Drop the "N warnings generated." chatter; keep diagnostics.
    out=$(printf "%s\n" "$out" | grep -vE "^[0-9]+ (warnings?|errors?)( and [0-9]+ (warnings?|errors?))? generated\.$" || true)
    [[ -n $out ]] && printf "%s\n" "$out"
    if [[ $rc == 0 && -z $out ]]; then
      for k in "$fast" "$key"; do [[ -n $k ]] && touch "$3/$k"; done
    fi
    exit "$rc"' "$clang_tidy" "$tidy_db" "$extra_checks" "$cache_dir" "$root" | tee "$log" || status=$?

# Belt and braces: a warning that was somehow not promoted to an error still fails the run.
if ((status != 0)) || grep -qE ': (warning|error):' "$log"; then
  n=$(grep -cE ': (warning|error):' "$log" || true)
  echo "run-clang-tidy: FAILED ($n findings)" >&2
  exit 1
fi
echo "run-clang-tidy: clean"

# --record: write the keys of every checked file to .ci/tidy-clean.txt (after a clean run).
# The fast key where the build has one, else the slow one.
if [[ $record == 1 ]]; then
  printf '%s\0' "${files[@]}" |
    xargs -0 -n1 -P"$jobs" bash -c '
      fast=$(awk -F "\t" -v f="$5" "\$1 == f { print \$2 }" "$4")
      if [[ -n $fast ]]; then echo "$fast"; else python3 "$0" key "$1" "$5" "$3" "$2"; fi' \
      "$root/scripts/tidy-key.py" "$tidy_db/compile_commands.json" "$extra_checks" "$root" \
      "$tidy_db/keys.tsv" |
    sort -u > "$root/.ci/tidy-clean.txt.tmp"
  mv "$root/.ci/tidy-clean.txt.tmp" "$root/.ci/tidy-clean.txt"
  echo "run-clang-tidy: recorded $(wc -l < "$root/.ci/tidy-clean.txt") keys in .ci/tidy-clean.txt"
fi
