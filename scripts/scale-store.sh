#!/usr/bin/env bash
# The scale benchmark of docs/scale.md ("A real store on disk"): builds a generated Mars
# store of ROWS × 2·ROWS samples (default 65536 × 131072: 8.6e9 samples, about 46 GB with
# its pyramid), then measures
#   1. the build: wall time, CPU time, peak RSS, file size, samples/s and bytes/sample;
#   2. the same data per sample as a COG: gdal_translate -of COG from the store's level 0
#      (GDAL's HDF5 driver), uncompressed and with COG's default LZW, and regolith import of
#      the uncompressed COG, on a store of at most --cog-rows rows (the sample-count-scaled
#      run: a full-size COG would need the disk twice);
#   3. a rover traverse on the store through a 64 MiB cache (bench/procedural_bench with
#      REGOLITH_SCALE_STORE): six wheels every 1 cm along 20 km, heights and heights + normals,
#      cold and warm, as wheel queries/s, patch loads, the peak resident bytes, the bytes
#      the cache loaded and the bytes read from the disk (the page cache dropped before each
#      cold run when run as root);
#   4. a fly-over of the store through a 256 MiB cache (bench/flyover_bench with
#      REGOLITH_SCALE_STORE): 90 frames from two radii down to 500 m at 1280 × 720 headless,
#      frame times, frames drawn coarser while loading, patch loads, the peak resident bytes
#      against the budget, the process's RSS at the start and at its peak, and the bytes
#      read from the disk (the page cache dropped first when run as root).
# A benchmark run by hand, never a CI test at full size (tests/tools runs it at 512 rows).
# It refuses to start without the disk it needs, and removes what it wrote unless --keep.
#
#   bash scripts/scale-store.sh [--rows N] [--cog-rows N] [--dir DIR] [--build DIR] [--keep]
#                               [--keep-page-cache]
#
# --keep-page-cache leaves the kernel's page cache alone (the check at 512 rows, and a user
# who is not root): cold runs may then find the store in it.
#
# Prints a Markdown table per step on stdout (progress and tool output on stderr).
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
rows=65536
cog_rows=8192
dir=${TMPDIR:-/tmp}/regolith-scale
build=$root/build
keep=0
drop=1
usage() { awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; }
while (($#)); do
  case $1 in
    --rows) rows=${2:?--rows needs a number}; shift 2 ;;
    --cog-rows) cog_rows=${2:?--cog-rows needs a number}; shift 2 ;;
    --dir) dir=${2:?--dir needs a folder}; shift 2 ;;
    --build) build=${2:?--build needs a folder}; shift 2 ;;
    --keep) keep=1; shift ;;
    --keep-page-cache) drop=0; shift ;;
    -h | --help) usage; exit 0 ;;
    *) echo "scale-store: unknown argument '$1', expected --rows, --cog-rows, --dir, --build, --keep or --keep-page-cache" >&2; exit 2 ;;
  esac
done
for v in rows cog_rows; do
  if ! [[ ${!v} =~ ^[0-9]+$ ]] || ((${!v} < 2 || ${!v} > 1048576)); then
    echo "scale-store: --${v/_/-} is '${!v}', expected a whole number in 2 .. 1048576" >&2
    exit 2
  fi
done
((cog_rows > rows)) && cog_rows=$rows
regolith=$build/tools/regolith
bench=$build/bench/procedural_bench
flyover=$build/bench/flyover_bench
for exe in "$regolith" "$bench" "$flyover"; do
  [[ -x $exe ]] || { echo "scale-store: $exe not found; build it first (cmake --build $build --target regolith procedural_bench flyover_bench; the benches need -DREGOLITH_BUILD_BENCH=ON)" >&2; exit 2; }
done
for tool in gdal_translate /usr/bin/time python3; do
  command -v "$tool" >/dev/null || { echo "scale-store: $tool not found (scripts/install-deps.sh installs it)" >&2; exit 2; }
done

mkdir -p "$dir"
# Disk: the store (level 0 plus a pyramid of a third more, uncompressed float32), the COG
# source store, its import and the COGs (at most 1.4 × the source's level 0), 2 GiB spare.
need=$(python3 -c "r=$rows; c=$cog_rows; print(int(r*2*r*4*4/3 + c*2*c*4*(2*4/3 + 2*1.4) + 2**31))")
avail=$(df -B1 --output=avail "$dir" | tail -1 | tr -d ' ')
if ((avail < need)); then
  echo "scale-store: $dir has $((avail >> 30)) GiB free, expected at least $((need >> 30)) GiB for --rows $rows (use --dir on a larger disk, or fewer --rows)" >&2
  exit 1
fi
cleanup() { ((keep)) || rm -f "$dir/scale.h5" "$dir/cog-src.h5" "$dir/cog-import.h5" "$dir"/cog-*.tif "$dir"/*.time; }
trap cleanup EXIT

# Runs "$@" under /usr/bin/time and sets T_WALL (s), T_CPU (user + system s) and T_RSS (peak
# KiB); stops the script naming the command if it fails.
timed() {
  local out=$1
  shift
  if ! /usr/bin/time -f '%e %U %S %M' -o "$out" "$@" >&2; then
    echo "scale-store: failed: $*" >&2
    exit 1
  fi
  local user sys
  read -r T_WALL user sys T_RSS <"$out"
  T_CPU=$(awk -v u="$user" -v s="$sys" 'BEGIN { printf "%.2f", u + s }')
}
size_of() { stat -c %s "$1"; }
fmt() { python3 -c "import sys; print(format(float(sys.argv[1]), sys.argv[2]))" "$1" "$2"; }

machine="$(nproc) cores, $(awk '/MemTotal/ {printf "%.1f GiB", $2 / 1048576}' /proc/meminfo) RAM, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //')"
echo "# scale-store: $rows × $((2 * rows)) samples"
echo
echo "$(date -u '+%Y-%m-%d %H:%M UTC'), commit $(git -C "$root" describe --always --dirty 2>/dev/null || echo unknown), $machine; $((avail >> 30)) GiB free in $dir at start."
echo

# 1. The build.
echo "scale-store: generating $dir/scale.h5 ($rows rows)" >&2
timed "$dir/gen.time" "$regolith" generate mars-planet --size "$rows" --out "$dir/scale.h5"
wall=$T_WALL cpu=$T_CPU rss=$T_RSS
samples=$((rows * 2 * rows))
bytes=$(size_of "$dir/scale.h5")
echo "## Build"
echo
echo "| store | samples | wall s | CPU s | peak RSS MiB | file GiB | samples/s (wall) | bytes/sample |"
echo "|---|---:|---:|---:|---:|---:|---:|---:|"
echo "| \`regolith generate mars-planet --size $rows\` | $samples | $wall | $cpu | $((rss / 1024)) | $(fmt "$(python3 -c "print($bytes / 2**30)")" .2f) | $(fmt "$(python3 -c "print($samples / max($wall, 0.01))")" .3g) | $(fmt "$(python3 -c "print($bytes / $samples)")" .3f) |"
echo

# 2. The same data per sample as a COG, at --cog-rows.
src=$dir/scale.h5
csamples=$((cog_rows * 2 * cog_rows))
echo "## The same data per sample: Regolith against a COG ($cog_rows × $((2 * cog_rows)) samples)"
echo
echo "| what | wall s | CPU s | peak RSS MiB | bytes/sample | samples/s (wall) |"
echo "|---|---:|---:|---:|---:|---:|"
if ((cog_rows < rows)); then
  echo "scale-store: generating $dir/cog-src.h5 ($cog_rows rows) for the COG comparison" >&2
  timed "$dir/gen2.time" "$regolith" generate mars-planet --size "$cog_rows" --out "$dir/cog-src.h5"
  wall2=$T_WALL cpu2=$T_CPU rss2=$T_RSS
  src=$dir/cog-src.h5
else
  wall2=$wall cpu2=$cpu rss2=$rss
fi
echo "| \`regolith generate mars-planet --size $cog_rows\` (computes the samples too) | $wall2 | $cpu2 | $((rss2 / 1024)) | $(fmt "$(python3 -c "print($(size_of "$src") / $csamples)")" .3f) | $(fmt "$(python3 -c "print($csamples / max($wall2, 0.01))")" .3g) |"
# The store's georeferencing, which GDAL's HDF5 driver does not read from it: the generated
# planet spans -180..180 and -90..90 on the Mars sphere (regolith info).
georef=(-a_srs "+proj=longlat +R=3396190 +no_defs" -a_ullr -180 90 180 -90)
for compress in NONE LZW; do
  out=$dir/cog-$compress.tif
  timed "$dir/cog.time" gdal_translate -q -of COG -co "COMPRESS=$compress" -co NUM_THREADS=ALL_CPUS "${georef[@]}" "HDF5:\"$src\"://grids/mars/level0" "$out"
  w=$T_WALL c=$T_CPU r=$T_RSS
  echo "| \`gdal_translate -of COG -co COMPRESS=$compress\` from the store's level 0 | $w | $c | $((r / 1024)) | $(fmt "$(python3 -c "print($(size_of "$out") / $csamples)")" .3f) | $(fmt "$(python3 -c "print($csamples / max($w, 0.01))")" .3g) |"
  if [[ $compress == NONE ]]; then
    # The same work the other way: Regolith's import of that COG into a store with its pyramid.
    timed "$dir/imp.time" "$regolith" import "$out" --out "$dir/cog-import.h5"
    w=$T_WALL c=$T_CPU r=$T_RSS
    echo "| \`regolith import\` of that COG (store and pyramid) | $w | $c | $((r / 1024)) | $(fmt "$(python3 -c "print($(size_of "$dir/cog-import.h5") / $csamples)")" .3f) | $(fmt "$(python3 -c "print($csamples / max($w, 0.01))")" .3g) |"
    rm -f "$dir/cog-import.h5"
  fi
  rm -f "$out"
done
echo

# 3. The rover on the store. Each run is a process of its own; before each cold one the
# kernel's page cache is dropped where this user may (root), so the store comes from the disk.
page_cache="dropped before each cold run"
((drop)) || page_cache="kept (--keep-page-cache): a cold run may find the store in it"
drop_page_cache() {
  ((drop)) || return 0
  sync
  if ! { echo 1 >/proc/sys/vm/drop_caches; } 2>/dev/null; then
    page_cache="not dropped (this user may not): a cold run may find the store in the page cache"
  fi
}
echo "scale-store: the rover traverse on $dir/scale.h5" >&2
runs=()
for run in heights_cold heights_warm surfaces_cold surfaces_warm; do
  [[ $run == *_cold ]] && drop_page_cache
  runs+=("$(REGOLITH_SCALE_STORE="$dir/scale.h5" "$bench" --benchmark_filter="^store/traverse/$run" --benchmark_format=json)")
done
echo "## A rover traverse on the store (64 MiB cache; goal ≥ 20 M wheel queries/s)"
echo
echo "Page cache: $page_cache."
echo
python3 - "${runs[@]}" <<'PY'
import json, sys
print("| benchmark | wheel queries/s | patch loads | evictions | peak resident MiB | MiB loaded | "
      "disk MiB read |")
print("|---|---:|---:|---:|---:|---:|---:|")
for run in sys.argv[1:]:
    for b in json.loads(run)["benchmarks"]:
        print(f"| `{b['name']}` | {b['items_per_second'] / 1e6:.1f} M | {b['patch_loads']:.0f} | "
              f"{b['evictions']:.0f} | {b['peak_resident_MiB']:.1f} | {b['MiB_loaded']:.1f} | "
              f"{b['disk_MiB_read']:.1f} |")
PY
echo

# 4. A fly-over of the store.
echo "scale-store: a fly-over of $dir/scale.h5" >&2
drop_page_cache
json=$(REGOLITH_SCALE_STORE="$dir/scale.h5" "$flyover" --benchmark_filter='^store/flyover' --benchmark_format=json)
echo "## A fly-over of the store (256 MiB cache; 1280 × 720, llvmpipe)"
echo
echo "Page cache: ${page_cache/each cold run/the fly-over}."
echo
python3 - "$json" <<'PY'
import json, sys
rows = json.loads(sys.argv[1])["benchmarks"]
print("| benchmark | frames | frame ms median | p90 | max | frames drawn coarser | patch loads | "
      "MiB loaded | peak resident MiB | budget MiB | RSS at start MiB | peak RSS MiB | "
      "disk MiB read |")
print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
for b in rows:
    print(f"| `{b['name']}` | {b['frames']:.0f} | {b['frame_ms_median']:.1f} | {b['frame_ms_p90']:.1f} | "
          f"{b['frame_ms_max']:.1f} | {b['frames_coarser']:.0f} | {b['patch_loads']:.0f} | "
          f"{b['MiB_loaded']:.1f} | {b['peak_resident_MiB']:.1f} | {b['budget_MiB']:.0f} | "
          f"{b['rss_before_MiB']:.0f} | {b['peak_rss_MiB']:.0f} | {b['disk_MiB_read']:.1f} |")
PY
echo
echo "Commands: \`bash scripts/scale-store.sh --rows $rows --cog-rows $cog_rows\` (docs/scale.md)."
