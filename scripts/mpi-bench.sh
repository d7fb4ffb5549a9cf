#!/usr/bin/env bash
# 1 against 2 MPI ranks (docs/scale.md, "Measured: 1 against 2 ranks"): builds an 8192² float32
# GeoTIFF of smooth noise and the same raster cut into 64 tiles of 1024² (once, in DIR), then
# runs `mpirun -np 1`, `mpirun -np 2` (regolith-mpi import) and `regolith import --threads 1`
# on each input, alternated, ROUNDS times, and prints wall and CPU seconds per run and each
# part's time. Finally checks that the last round's three stores of the mosaic are the same
# store (tests/tools/test_mpi_import.py's assert_same_store). Needs both cores idle to mean
# anything; it is a benchmark, not a test.
#
#   bash scripts/mpi-bench.sh [DIR, default /tmp/mpibench] [BUILD_DIR, default build]
# Environment: ROUNDS (default 3), DEFLATE (the deflate level, default 6). As root, OpenMPI
# needs OMPI_ALLOW_RUN_AS_ROOT=1 and OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 (set here).
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
dir=${1:-/tmp/mpibench}
build=$(cd "${2:-$root/build}" && pwd)
rounds=${ROUNDS:-3}
deflate=${DEFLATE:-6}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
mkdir -p "$dir/tiles"
cd "$dir"
if [[ ! -f input_8192.tif ]]; then
  /usr/bin/python3 - <<'PY'
import numpy as np
from osgeo import gdal, osr
n = 8192; rng = np.random.default_rng(1); z = np.zeros((n, n), np.float32)
for o in range(8):  # octaves: bilinear value noise on (2^(o+2) + 1)^2 knots
    k = 2 ** (o + 2); g = rng.normal(0, 2000.0 / (o + 1) ** 1.5, (k + 1, k + 1)).astype(np.float32)
    t = np.linspace(0, k, n, dtype=np.float32); i = np.minimum(t.astype(int), k - 1); f = t - i
    r = g[i] * (1 - f)[:, None] + g[i + 1] * f[:, None]
    z += r[:, i] * (1 - f)[None, :] + r[:, i + 1] * f[None, :]
z += rng.normal(0, 0.5, (n, n)).astype(np.float32)
ds = gdal.GetDriverByName("GTiff").Create("input_8192.tif.tmp", n, n, 1, gdal.GDT_Float32,
                                          ["TILED=YES", "BLOCKXSIZE=256", "BLOCKYSIZE=256"])
ds.SetGeoTransform((0.0, 0.01, 0, 40.0, 0, -0.01))
s = osr.SpatialReference(); s.SetFromUserInput("+proj=longlat +R=3396190 +no_defs")
ds.SetProjection(s.ExportToWkt()); ds.GetRasterBand(1).WriteArray(z); ds = None
PY
  mv input_8192.tif.tmp input_8192.tif
fi
for y in 0 1 2 3 4 5 6 7; do
  for x in 0 1 2 3 4 5 6 7; do
    t=tiles/t_${y}_${x}.tif
    [[ -f $t ]] || gdal_translate -q -of GTiff -co TILED=YES -srcwin $((x * 1024)) $((y * 1024)) \
      1024 1024 input_8192.tif "$t"
  done
done

for ((round = 1; round <= rounds; ++round)); do
  for input in raster tiles; do
    if [[ $input == raster ]]; then src=(input_8192.tif); else src=(tiles/t_*.tif); fi
    for np in 1 2; do
      rm -f "o$np.h5"
      /usr/bin/time -f "round $round $input np$np wall %e cpu %U+%S" \
        mpirun -np "$np" "$build/tools/mpi/regolith-mpi" import "${src[@]}" --out "o$np.h5" \
        --deflate "$deflate" >"log-$input-np$np-$round.txt" 2>&1
      tail -1 "log-$input-np$np-$round.txt"
      grep 'ranks:' "log-$input-np$np-$round.txt" || true
    done
    rm -f t1.h5
    /usr/bin/time -f "round $round $input import1 wall %e cpu %U+%S" \
      "$build/tools/regolith" import "${src[@]}" --out t1.h5 --deflate "$deflate" --threads 1 \
      >"log-$input-t1-$round.txt" 2>&1
    tail -1 "log-$input-t1-$round.txt"
  done
done
cd "$root/tests/tools"
/usr/bin/python3 - "$dir" <<'PY'
import sys
import test_mpi_import as t
d = sys.argv[1]
t.assert_same_store(d + "/t1.h5", d + "/o2.h5")
t.assert_same_store(d + "/o1.h5", d + "/o2.h5")
print("mosaic: regolith import --threads 1, 1 rank and 2 ranks wrote the same store")
PY
