#!/usr/bin/env python3
"""Per-level storage size and patch read time of stores, with h5py (docs/import.md).

For each store: the bytes HDF5 stores for every level of its grid (compressed), then the mean
time to read 64 random 256 x 256 patches of level 0 with the chunk cache off (the same patches
in every store, seeded). Used to compare the deflate and zfp codecs on the import benchmark's
input:

    build/tools/regolith import $TMPDIR/regolith-import-bench/input_8192.tif --out i_def.h5 \\
        --grid g --deflate 6
    build/tools/regolith import $TMPDIR/regolith-import-bench/input_8192.tif --out i_zfp.h5 \\
        --grid g --compression zfp
    /usr/bin/python3 bench/read_patches.py i_def.h5 i_zfp.h5
"""

import sys
import time

import h5py
import numpy as np


def main():
    if len(sys.argv) < 2:
        sys.exit("usage: read_patches.py STORE.h5 [STORE.h5 ...]")
    rng = np.random.default_rng(3)
    picks = None
    for path in sys.argv[1:]:
        with h5py.File(path, "r", rdcc_nbytes=0) as f:
            name = next(iter(f["grids"]))
            g = f["grids"][name]
            sizes = [g[f"level{k}"].id.get_storage_size() / 1e6 for k in range(int(g.attrs["levels"]))]
            d = g["level0"]
            rows, cols = d.shape[0] // 256, d.shape[1] // 256
            if picks is None:
                picks = [(int(rng.integers(0, rows)), int(rng.integers(0, cols))) for _ in range(64)]
            t = time.perf_counter()
            for i, j in picks:
                d[i * 256:(i + 1) * 256, j * 256:(j + 1) * 256]
            ms = (time.perf_counter() - t) / len(picks) * 1e3
            print(f"{path}: grid '{name}', levels (MB) {[round(s, 1) for s in sizes]}, "
                  f"{ms:.2f} ms per 256x256 patch of level 0")


if __name__ == "__main__":
    main()
