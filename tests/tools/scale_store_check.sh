#!/usr/bin/env bash
# ctest scale_store_script: scripts/scale-store.sh (docs/scale.md) at 512 rows keeps working,
# cleans up after itself, and refuses a run the disk cannot hold or a bad argument with a
# clear message. Usage: scale_store_check.sh SOURCE_DIR BUILD_DIR
set -uo pipefail
src=$1 build=$2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail() { echo "scale_store_check: $*" >&2; exit 1; }

bash "$src/scripts/scale-store.sh" --rows 512 --cog-rows 256 --dir "$tmp/run" --build "$build" \
  --keep-page-cache >"$tmp/out.md" 2>"$tmp/err" || { cat "$tmp/err" >&2; fail "the 512-row run failed"; }
# shellcheck disable=SC2016 # the backticks are literal Markdown
for want in '| `regolith generate mars-planet --size 512` | 524288 |' \
  '| `regolith generate mars-planet --size 256` (computes the samples too) |' \
  '| `gdal_translate -of COG -co COMPRESS=NONE` from the store' \
  '| `gdal_translate -of COG -co COMPRESS=LZW` from the store' '| `regolith import` of that COG' \
  '| `store/traverse/heights_cold/iterations:1` |' '| `store/traverse/surfaces_warm/iterations:3` |' \
  '| `store/flyover/iterations:1` | 90 |'; do
  grep -qF -- "$want" "$tmp/out.md" || { cat "$tmp/out.md" >&2; fail "no line '$want'"; }
done
# The page cache left alone, said under both the traverse's and the fly-over's table.
[[ $(grep -cxF 'Page cache: kept (--keep-page-cache): a cold run may find the store in it.' "$tmp/out.md") == 2 ]] ||
  fail "the page cache's state is not said under both tables"
# Every traverse row has a positive rate in M wheel queries/s.
awk -F'|' '/store\/traverse/ { gsub(/[ M]/, "", $3); if (!($3 > 0)) bad = 1 } END { exit bad }' \
  "$tmp/out.md" || fail "a traverse row without a positive rate"
# The fly-over: positive frame times, the cache never above its 256 MiB budget, and the
# process's peak resident set at least its resident set at the start.
awk -F'|' '/store\/flyover/ { if (!($4 > 0 && $6 >= $4 && $10 > 0 && $10 <= $11 && $11 == 256 && $12 > 0 && $13 >= $12)) bad = 1; n++ }
  END { exit bad || n != 1 }' "$tmp/out.md" || { cat "$tmp/out.md" >&2; fail "a fly-over row with a bad frame time or resident bytes"; }
leftover=$(find "$tmp/run" -name '*.h5' -o -name '*.tif' -o -name '*.time')
[[ -z $leftover ]] || fail "files left behind: $leftover"

# A run the disk cannot hold: refused before anything is written.
if bash "$src/scripts/scale-store.sh" --rows 1048576 --dir "$tmp/big" --build "$build" \
  >/dev/null 2>"$tmp/err"; then
  fail "a 1048576-row run was not refused"
fi
grep -q "GiB free, expected at least .* GiB for --rows 1048576" "$tmp/err" || {
  cat "$tmp/err" >&2
  fail "no clear message for a disk too small"
}
[[ -z $(find "$tmp/big" -type f) ]] || fail "the refused run wrote files"

# A bad argument names itself and what is expected.
if bash "$src/scripts/scale-store.sh" --rows twelve --build "$build" 2>"$tmp/err"; then
  fail "--rows twelve was accepted"
fi
grep -qF -- "--rows is 'twelve', expected a whole number in 2 .. 1048576" "$tmp/err" || {
  cat "$tmp/err" >&2
  fail "no clear message for --rows twelve"
}
if bash "$src/scripts/scale-store.sh" --drop-caches --build "$build" 2>"$tmp/err"; then
  fail "--drop-caches was accepted"
fi
grep -qF -- "unknown argument '--drop-caches', expected --rows, --cog-rows, --dir, --build, --keep or --keep-page-cache" "$tmp/err" || {
  cat "$tmp/err" >&2
  fail "no clear message for an unknown argument"
}
echo "scale_store_check: ok"
