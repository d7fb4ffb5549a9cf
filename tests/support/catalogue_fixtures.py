"""Catalogue scenes for the tests of composition from the command line
(tests/tools/test_cli_catalogue.py) and from Python (tests/python/test_compose.py).

Stores are written by h5py alone, following docs/store-format.md (Regolith's own writer plays
no part in them), and the composition rule of docs/composition.md is written out in numpy
for scenes simple enough to have a closed form: constant-height grids on a sphere, one
feathered border."""

import os

import h5py
import numpy as np

MOON = ("Moon", 1737400.0, 1737400.0)


def _grid_attrs(kind, rows, cols, x0, y0, dx, dy, body, patch, nodata, latitude_type):
    name, a, b = body
    attrs = {
        "format_version": np.array([1, 0], dtype="<i4"), "kind": kind,
        "rows": np.uint64(rows), "cols": np.uint64(cols), "x0": float(x0), "y0": float(y0),
        "spacing": np.array([dx, dy], dtype="<f8"), "units": "m", "sample_type": "float32",
        "scale": 1.0, "offset": 0.0, "body": name, "equatorial_radius": a, "polar_radius": b,
        "latitude_type": latitude_type, "levels": np.uint64(1),
        "patch_shape": np.array([patch, patch], dtype="<u8"),
    }
    if nodata is not None:
        attrs["nodata"] = np.float32(nodata)
    return attrs


def write_store(path, grids):
    """Writes `grids` ({name: (attrs, heights)}) into a new store at `path`."""
    with h5py.File(path, "w") as f:
        f.attrs["regolith_store"] = "made by h5py"
        f.attrs["format_version"] = np.array([1, 0], dtype="<i4")
        for name, (attrs, heights) in grids.items():
            g = f.create_group(f"grids/{name}")
            for k, v in attrs.items():
                g.attrs[k] = v
            patch = int(attrs["patch_shape"][0])
            g.create_dataset("level0", data=np.asarray(heights, dtype="<f4"),
                             chunks=(min(patch, heights.shape[0]), min(patch, heights.shape[1])))
    return path


def planet_grid(heights, west, north, step, body=MOON, patch=16, nodata=None,
                latitude_type="planetodetic"):
    """A latitude/longitude grid whose pixel extent starts at (west, north) degrees, `step`
    degrees per sample: sample (r, c) is centred at lat north - (r + 0.5) step, lon
    west + (c + 0.5) step."""
    heights = np.asarray(heights, dtype=np.float64)
    rows, cols = heights.shape
    attrs = _grid_attrs("planet", rows, cols, west + 0.5 * step, north - 0.5 * step, step, step,
                        body, patch, nodata, latitude_type)
    return attrs, heights


def tangent_plane_grid(heights, spacing, origin_lat, origin_lon, body=MOON, patch=16):
    """A DEM on the tangent plane at (origin_lat, origin_lon), planetodetic, centred on the
    plane's origin: sample (r, c) at x = (c - (cols - 1) / 2) spacing, y = ((rows - 1) / 2 - r)
    spacing metres."""
    heights = np.asarray(heights, dtype=np.float64)
    rows, cols = heights.shape
    attrs = _grid_attrs("dem", rows, cols, -0.5 * (cols - 1) * spacing, 0.5 * (rows - 1) * spacing,
                        spacing, spacing, body, patch, None, "planetodetic")
    attrs.update({"placement": "local_tangent_plane", "origin_lat_deg": float(origin_lat),
                  "origin_lon_deg": float(origin_lon), "origin_height": 0.0,
                  "heading_deg": 0.0})
    return attrs, heights


def smoothstep(t):
    t = np.clip(t, 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


# ---- the composition rule written out in numpy (docs/composition.md), for simple scenes ----

DEG = np.pi / 180.0


def planet_coverage(lat, lon, extent, feather_m, radius):
    """Coverage of a regional latitude/longitude grid on a sphere of `radius` with pixel
    extent (west, east, south, north) degrees and a border feather of `feather_m` metres:
    smoothstep of the distance to the nearest edge (along the meridian, or along the
    parallel, metres on the sphere) over the feather; 0 outside the extent."""
    west, east, south, north = extent
    lat = np.asarray(lat, dtype=np.float64)
    lon = np.asarray(lon, dtype=np.float64)
    along_parallel = radius * np.cos(lat * DEG) * DEG
    d = np.minimum.reduce([(north - lat) * radius * DEG, (lat - south) * radius * DEG,
                           (lon - west) * along_parallel, (east - lon) * along_parallel])
    inside = (lat >= south) & (lat <= north) & (lon >= west) & (lon <= east)
    return np.where(inside, smoothstep(d / feather_m), 0.0)


def planet_coverage_gradient(lat, lon, extent, feather_m, radius):
    """(d coverage / d east, d coverage / d north) per metre of planet_coverage(), where the
    west edge is the nearest one (the only case the tests use)."""
    west = extent[0]
    d = (lon - west) * radius * np.cos(lat * DEG) * DEG
    t = d / feather_m
    ds = 6.0 * t * (1.0 - t) / feather_m
    # Moving east by de metres moves the point de metres from the west edge; moving north
    # by dn metres shrinks the parallel's radius: d(d)/dn = -(lon - west) sin(lat) (radians).
    return ds, ds * (-(lon - west) * DEG * np.sin(lat * DEG))


def planet_quality(lat):
    """Kooima's projection quality of a square-pixel latitude/longitude grid on a sphere:
    the pixel's anisotropy and its scale distortion are cos(lat) and sqrt(cos(lat)), so
    alpha = 1 - |ln cos(lat)| / ln 8, clamped to [1e-3, 1]."""
    q = 1.0 - np.abs(np.log(np.cos(np.asarray(lat) * DEG))) / np.log(8.0)
    return np.clip(q, 1e-3, 1.0)


def enu_basis(lat, lon):
    """East, north and up unit vectors (body-fixed) of a point on a sphere."""
    la, lo = lat * DEG, lon * DEG
    east = np.array([-np.sin(lo), np.cos(lo), 0.0])
    north = np.array([-np.sin(la) * np.cos(lo), -np.sin(la) * np.sin(lo), np.cos(la)])
    up = np.array([np.cos(la) * np.cos(lo), np.cos(la) * np.sin(lo), np.sin(la)])
    return east, north, up


def tangent_plane_height(lat, lon, origin_lat, origin_lon, plane_height, radius):
    """Height above a sphere, along the normal at (lat, lon), of the plane parallel to the
    tangent plane at the origin and `plane_height` above it: (R + H) (u . u0) - R = h."""
    u = enu_basis(lat, lon)[2]
    u0 = enu_basis(origin_lat, origin_lon)[2]
    return (radius + plane_height) / float(np.dot(u, u0)) - radius


# ---- one scene on the Moon for both test files --------------------------------------------

GLOBAL_H, REGIONAL_H, SITE_H = 100.0, 250.0, 400.0
REGIONAL_EXTENT = (20.0, 30.0, 0.0, 10.0)  # west, east, south, north (degrees)
REGIONAL_STEP, GLOBAL_STEP = 0.25, 2.0
FEATHER_M = 60000.0
HOLE = (slice(18, 22), slice(30, 34))  # rows, cols of the regional grid that are NaN
SITE_ORIGIN = (-30.0, 40.0)            # lat, lon of the tangent-plane DEM's centre
SITE_SPACING, SITE_SIZE = 100.0, 101


def write_moon_scene(folder):
    """Writes, with h5py: global.h5 (a constant 2-degree global grid, GLOBAL_H), regional.h5
    (a constant 0.25-degree grid over REGIONAL_EXTENT, REGIONAL_H, NaN over HOLE, and the
    tangent-plane DEM 'site' at SITE_ORIGIN, SITE_H) and returns the regional heights."""
    write_store(os.path.join(folder, "global.h5"), {
        "global": planet_grid(np.full((90, 180), GLOBAL_H), -180.0, 90.0, GLOBAL_STEP)})
    regional = np.full((40, 40), REGIONAL_H)
    regional[HOLE] = np.nan
    write_store(os.path.join(folder, "regional.h5"), {
        "regional": planet_grid(regional, REGIONAL_EXTENT[0], REGIONAL_EXTENT[3], REGIONAL_STEP),
        "site": tangent_plane_grid(np.full((SITE_SIZE, SITE_SIZE), SITE_H), SITE_SPACING,
                                   *SITE_ORIGIN)})
    return regional


def regional_has_data(lat, lon, regional):
    """False where the bilinear stencil of the regional grid at (lat, lon) reaches a NaN
    sample (its four nearest sample centres), for points inside its extent."""
    west, _, _, north = REGIONAL_EXTENT
    rows, cols = regional.shape
    v = np.clip((north - np.asarray(lat)) / REGIONAL_STEP - 0.5, 0, rows - 1)
    u = np.clip((np.asarray(lon) - west) / REGIONAL_STEP - 0.5, 0, cols - 1)
    r0 = np.minimum(np.floor(v).astype(int), rows - 2)
    c0 = np.minimum(np.floor(u).astype(int), cols - 2)
    bad = np.zeros(np.shape(r0), dtype=bool)
    for dr in (0, 1):
        for dc in (0, 1):
            bad |= np.isnan(regional[r0 + dr, c0 + dc])
    return ~bad


def finest_wins_oracle(lat, lon, regional):
    """Composed heights, coverage of the regional grid, and contributor counts (datasets with a
    non-zero share) under "finest wins": H = c h_regional + (1 - c) h_global, so both
    contribute only inside the feather (0 < c < 1); past it the regional grid hides the
    global one."""
    c = planet_coverage(lat, lon, REGIONAL_EXTENT, FEATHER_M, MOON[1])
    c = np.where(regional_has_data(lat, lon, regional), c, 0.0)
    return c * REGIONAL_H + (1.0 - c) * GLOBAL_H, c, np.where((c > 0) & (c < 1), 2, 1)


def weighted_oracle(lat, lon, regional, power):
    """Composed heights under "weighted" with a tier ratio above the grids' spacing ratio (8),
    so that both are one tier: w = c q (finest spacing / spacing)^p; the two grids have the
    same quality at a latitude (square pixels), so it cancels. (With a tier ratio below 8 the
    regional grid is a tier of its own over the global one: finest_wins_oracle().)"""
    c = planet_coverage(lat, lon, REGIONAL_EXTENT, FEATHER_M, MOON[1])
    c = np.where(regional_has_data(lat, lon, regional), c, 0.0)
    q = planet_quality(lat)
    w_r = c * q
    w_g = q * (REGIONAL_STEP / GLOBAL_STEP) ** power
    return (w_r * REGIONAL_H + w_g * GLOBAL_H) / (w_r + w_g)
