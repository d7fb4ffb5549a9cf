#!/usr/bin/env python3
"""h5py as an outside oracle of the Regolith store format.

Runs write_fixture_store (the path to the binary is the first argument, or the environment
variable REGOLITH_WRITE_FIXTURE_STORE), then reads the store it wrote with h5py and numpy
ONLY, following docs/store-format.md: attributes, level datasets, chunk shapes, nodata,
scale/offset and pixel-centre geometry. Every value is checked against the analytic formulas
of tests/store/write_fixture_store.cpp. Any mismatch raises and the script exits non-zero.
For the transverse Mercator grid (utm.h5) PROJ, through GDAL's osr, turns the documented
placement attributes into each sample centre's longitude/latitude.

    /usr/bin/python3 tests/store/test_store_h5py.py build/tests/store/write_fixture_store
"""

import os
import subprocess
import sys
import tempfile
import warnings

import h5py
import numpy as np

CHECKS = 0


def check(cond, what):
    global CHECKS
    CHECKS += 1
    if not cond:
        raise AssertionError(what)


def check_close(got, want, what, rtol=2e-6, atol=2e-5):
    """Equal within float32 rounding; NaN where (and only where) want is NaN."""
    got = np.asarray(got, dtype=np.float64)
    want = np.asarray(want, dtype=np.float64)
    check(got.shape == want.shape, f"{what}: shape {got.shape}, expected {want.shape}")
    gn, wn = np.isnan(got), np.isnan(want)
    bad = np.argwhere(gn != wn)
    check(bad.size == 0, f"{what}: missing samples differ, first at {bad[:1].tolist()}")
    ok = ~wn
    err = np.abs(got[ok] - want[ok])
    tol = atol + rtol * np.abs(want[ok])
    if err.size:
        i = int(np.argmax(err - tol))
        check(bool(np.all(err <= tol)),
              f"{what}: max error {err.max()} (at flat index {i}), tolerance {tol[i]}")


# ---- the analytic content (same formulas as write_fixture_store.cpp) -----------------------

def victoria(x, y):
    h = 20.0 + 0.25 * x - 0.5 * y + 15.0 * np.sin(x / 23.0) * np.cos(y / 31.0)
    return np.where((x - 20.0) ** 2 + (y - 100.0) ** 2 < 30.0 ** 2, np.nan, h)


def mars(lon, lat):
    d = np.pi / 180.0
    h = 1000.0 * np.cos(lat * d) * np.sin(2.0 * lon * d) + 10.0 * lat
    missing = (lat > 85.0) | ((lon > 10.0) & (lon < 20.0) & (lat > -10.0) & (lat < 0.0))
    return np.where(missing, np.nan, h)


def tilt(x, y):
    return 3.0 + 0.125 * x - 0.0625 * y


# ---- reading a grid as docs/store-format.md says ------------------------------------------

def level_shape(g, k):
    """Level k has ceil(rows / 2^k) x ceil(cols / 2^k) samples."""
    f = 2 ** k
    return (-(-int(g.attrs["rows"]) // f), -(-int(g.attrs["cols"]) // f))


def centres(g, k):
    """Pixel-centre coordinates (x of each column, y of each row) of level k."""
    x0, y0 = float(g.attrs["x0"]), float(g.attrs["y0"])
    dx, dy = (float(v) for v in g.attrs["spacing"])
    f = 2 ** k
    shift = (f - 1) / 2.0
    rows, cols = level_shape(g, k)
    x = x0 + shift * dx + np.arange(cols) * f * dx
    y = y0 - shift * dy - np.arange(rows) * f * dy
    return x, y


def heights(g, k, rows=slice(None), cols=slice(None)):
    """Heights in metres of (part of) level k: offset + scale * stored, NaN where missing."""
    stored = g[f"level{k}"][rows, cols].astype(np.float64)
    missing = np.isnan(stored)
    if "nodata" in g.attrs:
        nodata = float(g.attrs["nodata"])
        if not np.isnan(nodata):
            missing |= stored == nodata
    h = float(g.attrs["offset"]) + float(g.attrs["scale"]) * stored
    h[missing] = np.nan
    return h


def mean2x2(fine):
    """The documented pyramid rule: 2x2 mean ignoring missing samples and samples beyond
    the edge; missing only if all of them are."""
    r, c = fine.shape
    pad = np.full((r + (r % 2), c + (c % 2)), np.nan)
    pad[:r, :c] = fine
    blocks = np.stack([pad[0::2, 0::2], pad[0::2, 1::2], pad[1::2, 0::2], pad[1::2, 1::2]])
    n = np.sum(~np.isnan(blocks), axis=0)
    s = np.nansum(blocks, axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(n > 0, s / np.maximum(n, 1), np.nan)


def text(v, what):
    """A text attribute as docs/store-format.md specifies it since format 1.4: a fixed-length
    UTF-8 string (h5py reads those as numpy bytes; a variable-length one would come as str)."""
    check(isinstance(v, (bytes, np.bytes_)), f"{what}: {v!r} is not a fixed-length string")
    return bytes(v).rstrip(b"\0").decode("utf-8")


# ---- checks ----------------------------------------------------------------------------------

def check_common(g, name, kind, rows, cols, x0, y0, spacing, patch, levels, nodata, body, a, b,
                 lat_type):
    def attr(key):
        check(key in g.attrs, f"{name}: attribute {key} missing")
        return g.attrs[key]

    check(list(attr("format_version")) == [1, 4], f"{name}: format_version")
    check(text(attr("kind"), "kind") == kind, f"{name}: kind")
    check(int(attr("rows")) == rows and int(attr("cols")) == cols, f"{name}: rows/cols")
    check(float(attr("x0")) == x0 and float(attr("y0")) == y0, f"{name}: x0/y0")
    check([float(v) for v in attr("spacing")] == spacing, f"{name}: spacing")
    check(text(attr("units"), "units") == "m", f"{name}: units")
    check(text(attr("sample_type"), "sample_type") == "float32", f"{name}: sample_type")
    check(float(attr("scale")) == 1.0 and float(attr("offset")) == 0.0, f"{name}: scale/offset")
    nd = float(attr("nodata"))
    check((np.isnan(nd) and nodata is None) or nd == nodata, f"{name}: nodata {nd}")
    check(text(attr("body"), "body") == body, f"{name}: body")
    check(float(attr("equatorial_radius")) == a and float(attr("polar_radius")) == b,
          f"{name}: radii")
    check(text(attr("latitude_type"), "latitude_type") == lat_type, f"{name}: latitude_type")
    check(int(attr("levels")) == levels, f"{name}: levels {attr('levels')}")
    check([int(v) for v in attr("patch_shape")] == patch, f"{name}: patch_shape")
    for k in range(levels):
        ds = g[f"level{k}"]
        shape = level_shape(g, k)
        check(ds.shape == shape, f"{name} level{k}: shape {ds.shape}, expected {shape}")
        check(ds.dtype == np.dtype("<f4"), f"{name} level{k}: dtype {ds.dtype}")
        chunks = (min(patch[0], shape[0]), min(patch[1], shape[1]))
        check(ds.chunks == chunks, f"{name} level{k}: chunks {ds.chunks}, expected {chunks}")
    check(f"level{levels}" not in g, f"{name}: a level beyond 'levels'")


def check_pyramid(g, name, levels):
    for k in range(1, levels):
        check_close(heights(g, k), mean2x2(heights(g, k - 1)), f"{name} level{k} vs 2x2 mean")


def check_victoria(g):
    check_common(g, "victoria", "dem", 301, 203, -101.0, 300.0, [1.0, 2.0], [64, 48], 4,
                 -32768.0, "Mars", 3396190.0, 3376200.0, "planetodetic")
    check(text(g.attrs["placement"], "placement") == "local_tangent_plane", "victoria: placement")
    for key, want in [("origin_lat_deg", -2.05), ("origin_lon_deg", -5.5),
                      ("origin_height", -1400.0), ("heading_deg", 0.0)]:
        check(float(g.attrs[key]) == want, f"victoria: {key}")
    x, y = centres(g, 0)
    X, Y = np.meshgrid(x, y)
    check_close(heights(g, 0), victoria(X, Y), "victoria level0 vs analytic")
    # Missing samples are stored as the nodata value, not NaN.
    raw = g["level0"][...]
    check(not np.isnan(raw).any(), "victoria: NaN stored although nodata is declared")
    check(int(np.sum(raw == np.float32(-32768.0))) == int(np.sum(np.isnan(victoria(X, Y)))),
          "victoria: nodata count")
    # One sample by hand: row 5, col 7 is x = -101 + 7*1 = -94 m, y = 300 - 5*2 = 290 m
    # (row-major, row 0 north); its transpose (row 7, col 5) is a different place.
    check_close(g["level0"][5, 7], victoria(-94.0, 290.0), "victoria (5, 7)")
    check_close(g["level0"][7, 5], victoria(-96.0, 286.0), "victoria (7, 5)")
    # The south-east corner, and a sample inside the missing disc (x = 20, y = 100).
    check_close(g["level0"][300, 202], victoria(101.0, -300.0), "victoria (300, 202)")
    check(g["level0"][100, 121] == np.float32(-32768.0), "victoria (100, 121) is nodata")
    # One whole chunk through a slice aligned to patch_shape.
    check_close(heights(g, 0, slice(64, 128), slice(48, 96)),
                victoria(X[64:128, 48:96], Y[64:128, 48:96]), "victoria chunk (1, 1)")
    check_pyramid(g, "victoria", 4)
    # Some coarse sample is missing (all four below are) and some is a partial mean.
    l1 = heights(g, 1)
    check(bool(np.isnan(l1).any()), "victoria level1 has missing samples")


def check_mars(g):
    check_common(g, "mars", "planet", 360, 720, -179.75, 89.75, [0.5, 0.5], [64, 48], 5, None,
                 "Mars", 3396190.0, 3376200.0, "planetocentric")
    check("placement" not in g.attrs, "mars: a planet grid has no placement")
    lon, lat = centres(g, 0)
    LON, LAT = np.meshgrid(lon, lat)
    h = heights(g, 0)
    check_close(h, mars(LON, LAT), "mars level0 vs analytic")
    check(bool(np.isnan(g["level0"][...]).any()), "mars: missing samples stored as NaN")
    # Row 0 is the north edge: latitude 89.75 (missing); row 359 is -89.75.
    check(np.isnan(g["level0"][0, 0]), "mars (0, 0) north cap is missing")
    check_close(g["level0"][359, 360], mars(0.25, -89.75), "mars (359, 360)")
    # Column 400 is longitude -179.75 + 200 = 20.25 degrees east.
    check_close(g["level0"][180, 400], mars(20.25, -0.25), "mars (180, 400)")
    check_pyramid(g, "mars", 5)


def check_tilt(g):
    check_common(g, "tilt", "dem", 97, 131, 1000.0, -2000.0, [5.0, 5.0], [64, 48], 3, None,
                 "Moon", 1737400.0, 1737400.0, "planetocentric")
    check(text(g.attrs["placement"], "placement") == "polar_stereographic", "tilt: placement")
    check(int(g.attrs["pole"]) == -1, "tilt: pole")
    check(float(g.attrs["lat_true_scale_deg"]) == -90.0, "tilt: lat_true_scale_deg")
    check("scale_factor" not in g.attrs, "tilt: only one of lat_true_scale_deg/scale_factor")
    for key in ("lon_centre_deg", "false_easting", "false_northing"):
        check(float(g.attrs[key]) == 0.0, f"tilt: {key}")
    # A plane: each level's full 2x2 samples equal the plane at the documented level centres.
    for k in range(3):
        x, y = centres(g, k)
        X, Y = np.meshgrid(x, y)
        rows, cols = level_shape(g, k)
        full_r = int(g.attrs["rows"]) // 2 ** k  # rows whose whole 2^k block exists
        full_c = int(g.attrs["cols"]) // 2 ** k
        check_close(heights(g, k)[:full_r, :full_c], tilt(X, Y)[:full_r, :full_c],
                    f"tilt level{k} vs plane at level centres", rtol=1e-6, atol=1e-4)
        check(full_r < rows or k == 0, f"tilt level{k}: has an odd partial row")
    check_pyramid(g, "tilt", 3)


def read_level0(path, grid, r0, c0, nr, nc):
    """docs/store-format.md, "Tiled grids": heights of level-0 rows r0..r0+nr-1, cols
    c0..c0+nc-1 of a tiled or plain grid (NaN where missing or uncovered)."""
    out = np.full((nr, nc), np.nan)
    with h5py.File(path, "r") as f:
        g = f["grids/" + grid]
        if "tile_count" not in g.attrs:
            a = g["level0"][r0:r0 + nr, c0:c0 + nc].astype(np.float64)
            nodata = float(g.attrs.get("nodata", np.nan))
            a[np.isnan(a) | (a == nodata)] = np.nan
            return g.attrs["offset"] + g.attrs["scale"] * a
        for i in range(int(g.attrs["tile_count"])):
            t = g[f"tiles/{i}"].attrs
            tr0, tc0, tr, tc = (int(t[k]) for k in ("row0", "col0", "rows", "cols"))
            a0, a1 = max(r0, tr0), min(r0 + nr, tr0 + tr)
            b0, b1 = max(c0, tc0), min(c0 + nc, tc0 + tc)
            if a0 >= a1 or b0 >= b1:
                continue
            if "external_file" in t:
                ext = os.path.join(os.path.dirname(path), text(t["external_file"], "external_file"))
                h = read_level0(ext, text(t["external_grid"], "external_grid"), a0 - tr0, b0 - tc0, a1 - a0, b1 - b0)
            else:
                a = g[f"tiles/{i}/level0"][a0 - tr0:a1 - tr0, b0 - tc0:b1 - tc0].astype(np.float64)
                nodata = float(g.attrs.get("nodata", np.nan))
                a[np.isnan(a) | (a == nodata)] = np.nan
                h = g.attrs["offset"] + g.attrs["scale"] * a
            out[a0 - r0:a1 - r0, b0 - c0:b1 - c0] = h
    return out


def mosaic_height(r, c):
    h = 5.0 + 0.5 * r - 0.25 * c + 3.0 * np.sin(c / 7.0)
    return np.where((r + c) % 37 == 0, np.nan, h)


def check_tiled(path):
    with h5py.File(path, "r") as f:
        check(list(f.attrs["format_version"]) == [1, 4], "tiled: root format_version")
        g = f["grids/mosaic"]
        check(list(g.attrs["format_version"]) == [1, 4], "tiled: grid format_version")
        check(int(g.attrs["tile_count"]) == 3, "tiled: tile_count")
        check("level0" not in g, "tiled: no level0 dataset")
        check(g["tiles/0/level0"].chunks == (64, 48), "tiled: tile 0 chunks")
        check(text(g["tiles/2"].attrs["external_file"], "external_file") == "tiled_ext.h5", "tiled: external_file")
        rows, cols = int(g.attrs["rows"]), int(g.attrs["cols"])
        R, C = np.meshgrid(np.arange(rows), np.arange(cols), indexing="ij")
        want = mosaic_height(R, C)
        want[130:, :] = np.nan  # no tile there
        got = read_level0(path, "mosaic", 0, 0, rows, cols)
        check_close(got, want, "tiled level0 vs analytic")
        # A window at the corner of all three tiles equals the same part of the whole.
        check_close(read_level0(path, "mosaic", 65, 45, 10, 10), got[65:75, 45:55],
                    "tiled corner window", rtol=0, atol=0)
        # Level 1: 2x2 means of the assembled mosaic, across tile borders.
        a = g["level1"][...].astype(np.float64)
        a[np.isnan(a) | (a == float(g.attrs["nodata"]))] = np.nan
        blocks = want.reshape(rows // 2, 2, cols // 2, 2)
        with warnings.catch_warnings():  # all-NaN blocks give NaN, as documented
            warnings.simplefilter("ignore", RuntimeWarning)
            mean = np.nanmean(blocks.transpose(0, 2, 1, 3).reshape(rows // 2, cols // 2, 4), axis=2)
        check_close(a, mean, "tiled level1 vs 2x2 means")


def check_utm(path):
    """docs/store-format.md, transverse_mercator: the heights written are a function of each
    sample centre's latitude/longitude, which PROJ computes here from the attributes."""
    from osgeo import osr

    with h5py.File(path, "r") as f:
        check(list(f.attrs["format_version"]) == [1, 4], "utm: root format_version")
        g = f["grids/utm"]
        a = g.attrs
        check(list(a["format_version"]) == [1, 4], "utm: grid format_version")
        check(text(a["placement"], "placement") == "transverse_mercator", "utm: placement")
        check(float(a["scale_factor"]) == 0.9996, "utm: scale_factor")
        check(float(a["false_northing"]) == 10000000.0, "utm: false_northing")
        for absent in ("pole", "lat_true_scale_deg", "projection_radius", "origin_lat_deg"):
            check(absent not in a, f"utm: no {absent}")
        ellps = f"+a={a['equatorial_radius']!r} +b={a['polar_radius']!r}"
        tm = (f"+proj=tmerc +lon_0={a['lon_centre_deg']!r} +lat_0={a['lat_origin_deg']!r} "
              f"+k_0={a['scale_factor']!r} +x_0={a['false_easting']!r} "
              f"+y_0={a['false_northing']!r} {ellps}")
        rows, cols = int(a["rows"]), int(a["cols"])
        dx, dy = a["spacing"]
        x, y = np.meshgrid(a["x0"] + np.arange(cols) * dx, a["y0"] - np.arange(rows) * dy)
        h = heights(g, 0)
    src, dst = osr.SpatialReference(), osr.SpatialReference()
    src.ImportFromProj4(tm)
    dst.ImportFromProj4(f"+proj=longlat {ellps}")
    dst.SetAxisMappingStrategy(osr.OAMS_TRADITIONAL_GIS_ORDER)
    ct = osr.CoordinateTransformation(src, dst)
    lonlat = np.array(ct.TransformPoints(np.column_stack([x.ravel(), y.ravel()])))
    lon, lat = lonlat[:, 0].reshape(rows, cols), lonlat[:, 1].reshape(rows, cols)
    check(abs(lat.mean() + 43.0) < 0.2 and abs(lon.mean() + 124.3) < 0.2, "utm: where it is")
    want = 1e6 * (lat + 43.0) + 1e6 * np.cos(np.radians(43.0)) * (lon + 124.5)
    check_close(h, want, "utm level0 vs PROJ's positions", rtol=0.0, atol=0.01)


ZFP_FILTER = 32013  # H5Z-ZFP, the codec "zfp" (docs/store-format.md, "Compression")


def filter_ids(ds):
    """The HDF5 filter ids of a dataset's pipeline, in order."""
    plist = ds.id.get_create_plist()
    return [plist.get_filter(i)[0] for i in range(plist.get_nfilters())]


def main():
    binary = sys.argv[1] if len(sys.argv) > 1 else os.environ.get("REGOLITH_WRITE_FIXTURE_STORE")
    if not binary:
        sys.exit("usage: test_store_h5py.py <write_fixture_store> "
                 "(or set REGOLITH_WRITE_FIXTURE_STORE)")
    # Uncompressed, then the ZFP codec (HDF5 filter 32013), which h5py decodes through the
    # H5Z-ZFP plugin in HDF5's default plugin directory: no import beyond h5py and numpy.
    for codec, filters in (("deflate", []), ("zfp", [ZFP_FILTER])):
        with tempfile.TemporaryDirectory(prefix="regolith-h5py-") as tmp:
            path = os.path.join(tmp, "fixture.h5")
            subprocess.run([binary, path, codec], check=True)
            check(os.path.exists(path), "the store exists")
            check(sorted(os.listdir(tmp)) == ["fixture.h5", "tiled.h5", "tiled_ext.h5", "utm.h5"],
                  "no temporary file left")
            with h5py.File(path, "r") as f:
                check(text(f.attrs["regolith_store"], "marker").startswith("Regolith terrain store"), "marker")
                check(list(f.attrs["format_version"]) == [1, 4], "root format_version")
                check(sorted(f["grids"].keys()) == ["mars", "tilt", "victoria"], "grid names")
                for name in ("victoria", "mars", "tilt"):
                    g = f["grids"][name]
                    for level in range(int(g.attrs["levels"])):
                        got = filter_ids(g[f"level{level}"])
                        check(got == filters, f"{codec}: {name} level{level} filters {got}, "
                              f"expected {filters}")
                check_victoria(f["grids/victoria"])
                check_mars(f["grids/mars"])
                check_tilt(f["grids/tilt"])
            check_tiled(os.path.join(tmp, "tiled.h5"))
            check_utm(os.path.join(tmp, "utm.h5"))
    print(f"test_store_h5py: OK ({CHECKS} checks, h5py {h5py.__version__}, "
          f"numpy {np.__version__})")


if __name__ == "__main__":
    main()
