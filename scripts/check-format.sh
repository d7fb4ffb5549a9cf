#!/usr/bin/env bash
# Fails if any C++ source or header is not formatted as .clang-format says (clang-format 14).
#
#   scripts/check-format.sh          check (CI)
#   scripts/check-format.sh --fix    reformat the same files in place
#
# CLANG_FORMAT overrides the binary (default: clang-format).
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"
clang_format=${CLANG_FORMAT:-clang-format}
command -v "$clang_format" >/dev/null || { echo "check-format: $clang_format not found" >&2; exit 2; }

dirs=()
for d in core topo store compose scenegraph rover gl clod render farfield scene demo tests tools bench examples bindings; do
  [[ -d $d ]] && dirs+=("$d")
done
files=()
if ((${#dirs[@]} > 0)); then
  mapfile -d '' files < <(find "${dirs[@]}" -type f \( -name '*.hpp' -o -name '*.cpp' \) -print0 | sort -z)
fi
if ((${#files[@]} == 0)); then
  echo "check-format: no C++ files"
  exit 0
fi

if [[ ${1:-} == --fix ]]; then
  printf '%s\0' "${files[@]}" | xargs -0 "$clang_format" -i
  echo "check-format: formatted ${#files[@]} files"
  exit 0
fi

echo "check-format: $("$clang_format" --version | grep -o 'version [0-9.]*'), ${#files[@]} files"
if ! printf '%s\0' "${files[@]}" | xargs -0 "$clang_format" --dry-run --Werror; then
  echo "check-format: FAILED; run scripts/check-format.sh --fix (or clang-format -i on the files above)" >&2
  exit 1
fi
echo "check-format: clean"
