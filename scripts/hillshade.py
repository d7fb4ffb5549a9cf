#!/usr/bin/python3
"""A hillshade PNG of one grid of a Regolith store, to look at generated or imported terrain.

Reads the grid's level dataset with h5py alone (docs/store-format.md), shades it with a sun
from the north-west (azimuth 315 deg, elevation 45 deg) over a colour ramp of height, and
draws missing samples in dark blue. DEMs only: x/y spacing in metres.

    scripts/hillshade.py STORE GRID OUT.png [--level K] [--window ROW0 COL0 ROWS COLS]
                         [--exaggeration Z] [--zoom N]

Needs numpy, h5py and Pillow (Debian: python3-numpy python3-h5py python3-pil).
"""
import argparse
import sys

import h5py
import numpy as np
from PIL import Image


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("store")
    p.add_argument("grid")
    p.add_argument("out")
    p.add_argument("--level", type=int, default=0)
    p.add_argument("--window", type=int, nargs=4, metavar=("ROW0", "COL0", "ROWS", "COLS"))
    p.add_argument("--exaggeration", type=float, default=1.0)
    p.add_argument("--zoom", type=int, default=1, help="enlarge N times (nearest neighbour)")
    a = p.parse_args()

    with h5py.File(a.store, "r") as f:
        g = f["grids"][a.grid]
        if g.attrs["kind"].decode() != "dem":
            print(f"hillshade.py: grid '{a.grid}' is not a DEM", file=sys.stderr)
            return 1
        dx, dy = (float(v) * 2**a.level for v in g.attrs["spacing"])
        level = g[f"level{a.level}"]
        if a.window:
            r0, c0, nr, nc = a.window
            z = level[r0:r0 + nr, c0:c0 + nc]
        else:
            z = level[...]
        z = float(g.attrs["offset"]) + float(g.attrs["scale"]) * z.astype(np.float64)
        nodata = float(g.attrs["nodata"])
        if not np.isnan(nodata):
            z[level.dtype.type(nodata) == z] = np.nan

    missing = np.isnan(z)
    filled = np.where(missing, np.nanmean(z), z) * a.exaggeration
    # Rows run south: north is −row, so dz/dnorth = −dz/drow.
    dzdx = np.gradient(filled, axis=1) / dx
    dzdn = -np.gradient(filled, axis=0) / dy
    az, el = np.radians(315.0), np.radians(45.0)
    sun = np.array([np.sin(az) * np.cos(el), np.cos(az) * np.cos(el), np.sin(el)])
    norm = np.sqrt(dzdx**2 + dzdn**2 + 1.0)
    shade = np.clip((-dzdx * sun[0] - dzdn * sun[1] + sun[2]) / norm, 0.0, 1.0)

    valid = z[~missing]
    lo, hi = (np.percentile(valid, [1, 99]) if valid.size else (0.0, 1.0))
    t = np.clip((np.where(missing, lo, z) - lo) / max(hi - lo, 1e-9), 0.0, 1.0)
    # Low: rust brown; high: pale ochre.
    low, high = np.array([120, 60, 40]), np.array([240, 210, 160])
    tint = low[None, None, :] * (1 - t[..., None]) + high[None, None, :] * t[..., None]
    rgb = tint * (0.25 + 0.75 * shade[..., None])
    rgb[missing] = (20, 30, 70)
    image = Image.fromarray(np.clip(rgb, 0, 255).astype(np.uint8))
    if a.zoom > 1:
        image = image.resize((image.width * a.zoom, image.height * a.zoom), Image.NEAREST)
    image.save(a.out)
    print(f"{a.out}: {z.shape[0]} x {z.shape[1]} px, heights {lo:.0f}..{hi:.0f} m (1-99 %), "
          f"{int(missing.sum())} missing")
    return 0


if __name__ == "__main__":
    sys.exit(main())
