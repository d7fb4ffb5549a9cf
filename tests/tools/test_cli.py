"""End-to-end tests of the `regolith` command (docs/cli.md), run by ctest through pytest.

The real binary writes and reads real stores. Oracles from outside the library:
- h5py + numpy read the same stores (docs/store-format.md) for `info --json` and for
  `query` (samples at centres, bilinear heights and normals computed in numpy);
- a store written by h5py itself (not by Regolith) with nodata, for the nodata rows;
- PROJ's `cct` for the geodesy of `--coords lonlat` on a tangent-plane DEM;
- GDAL (osgeo.gdal) reads the rasters that `import` converts and `info` describes: the
  imported samples must equal GDAL's ReadAsArray, missing exactly where GDAL says.

Environment: REGOLITH_BIN (the regolith binary), REGOLITH_FIXTURE_WRITER (tests/store's
write_fixture_store, which writes multi-grid and tiled stores), REGOLITH_FIXTURES_DIR (the
real DEM fixtures, tests/data/dem of the checkout by default).
"""

import hashlib
import json
import math
import os
import pty
import select
import subprocess
import sys
import zipfile

import h5py
import numpy as np
import pytest
from osgeo import gdal, osr

gdal.UseExceptions()

BIN = os.environ.get("REGOLITH_BIN", "regolith")
FIXTURE_WRITER = os.environ.get("REGOLITH_FIXTURE_WRITER", "")
DEM_FIXTURES = os.environ.get("REGOLITH_FIXTURES_DIR") or os.path.join(
    os.path.dirname(os.path.abspath(__file__)), "..", "data", "dem"
)


def dem_fixture(name):
    path = os.path.join(DEM_FIXTURES, name)
    assert os.path.exists(path), f"missing fixture {path} (set REGOLITH_FIXTURES_DIR)"
    return path


# `render` makes a GL context: under AddressSanitizer, LeakSanitizer's exit-time scan would
# report Mesa's (llvmpipe's) own allocations, unsymbolized, as it does for clod_tests
# (tests/clod/CMakeLists.txt), so render runs with leak detection off; ASan still checks them.
NO_LEAK_CHECK = {"ASAN_OPTIONS": os.environ.get("ASAN_OPTIONS", "") + ":detect_leaks=0"}


def run(*args, stdin=None, check=True, env_render=False):
    renders = env_render or (args and args[0] == "render")
    env = {**os.environ, **NO_LEAK_CHECK} if renders else None
    p = subprocess.run([BIN, *map(str, args)], input=stdin, capture_output=True, text=True,
                       timeout=300, env=env)
    if check and p.returncode != 0:
        raise AssertionError(f"regolith {' '.join(map(str, args))} failed ({p.returncode}):\n"
                             f"{p.stderr}")
    return p


def number_or_word(v):
    try:
        return float(v)
    except ValueError:
        return v  # query's reason column


def parse_csv(text):
    lines = text.strip("\n").split("\n")
    header = lines[0].split(",")
    rows = [[number_or_word(v) for v in line.split(",")] for line in lines[1:]]
    return header, rows


# ---- fixtures -------------------------------------------------------------------------------

@pytest.fixture(scope="session")
def work(tmp_path_factory):
    return tmp_path_factory.mktemp("cli")


@pytest.fixture(scope="session")
def victoria(work):
    path = work / "victoria.h5"
    p = run("generate", "victoria", "--out", path, "--size", 241, "--resolution", 5,
            "--patch", 64, "--seed", 3)
    assert p.stderr == ""  # no progress bar: stderr is not a terminal
    assert "victoria" in p.stdout
    return path


@pytest.fixture(scope="session")
def planet(work):
    path = work / "mars.h5"
    run("generate", "mars-planet", "--out", path, "--size", 60, "--patch", 32, "--seed", 5,
        "--deflate", 4)
    return path


@pytest.fixture(scope="session")
def h5py_store(work):
    """A DEM store written by h5py following docs/store-format.md, with nodata samples."""
    path = work / "handmade.h5"
    rows, cols = 40, 50
    r, c = np.mgrid[0:rows, 0:cols]
    data = (0.5 * c - 0.25 * r + 3.0 * np.sin(c / 7.0)).astype("<f4")
    data[10:14, 20:25] = -9999.0   # nodata value
    data[30, 5] = np.nan           # NaN is always missing
    with h5py.File(path, "w") as f:
        f.attrs["regolith_store"] = "made by h5py"
        f.attrs["format_version"] = np.array([1, 0], dtype="<i4")
        g = f.create_group("grids/hand")
        attrs = {
            "format_version": np.array([1, 0], dtype="<i4"), "kind": "dem",
            "rows": np.uint64(rows), "cols": np.uint64(cols), "x0": 100.0, "y0": 200.0,
            "spacing": np.array([2.0, 3.0]), "units": "m", "sample_type": "float32",
            "scale": 1.0, "offset": 0.0, "nodata": np.float32(-9999.0), "body": "Mars",
            "equatorial_radius": 3396190.0, "polar_radius": 3376200.0,
            "latitude_type": "planetodetic", "levels": np.uint64(1),
            "patch_shape": np.array([16, 16], dtype="<u8"), "placement": "local_tangent_plane",
            "origin_lat_deg": 10.0, "origin_lon_deg": 20.0, "origin_height": 0.0,
            "heading_deg": 0.0,
        }
        for k, v in attrs.items():
            g.attrs[k] = v
        g.create_dataset("level0", data=data, chunks=(16, 16))
    return path, data


@pytest.fixture(scope="session")
def fixture_stores(work):
    if not FIXTURE_WRITER:
        pytest.fail("REGOLITH_FIXTURE_WRITER is not set")
    path = work / "fixture.h5"
    subprocess.run([FIXTURE_WRITER, str(path)], check=True, timeout=300)
    return path, work / "tiled.h5"


def level0(path, grid):
    with h5py.File(path, "r") as f:
        return f[f"grids/{grid}/level0"][...].astype(np.float64)


def plain_attrs(obj):
    """An HDF5 object's attributes, text as str: since format 1.4 the store writes fixed-length
    strings, which h5py reads as bytes (stores written by h5py itself hold str)."""
    return {k: (v.decode() if isinstance(v, bytes) else v)
            for k, v in ((k, obj.attrs[k]) for k in obj.attrs)}


def attrs(path, grid):
    with h5py.File(path, "r") as f:
        g = f[f"grids/{grid}"]
        return plain_attrs(g)


# ---- --help ---------------------------------------------------------------------------------

@pytest.mark.parametrize("cmd,expect", [
    ([], ["generate", "import", "info", "query", "demo"]),
    (["generate"], ["mars-planet", "mars-cap", "mars-strip", "victoria"]),
    (["generate", "mars-cap"], ["--pole", "--min-lat", "--resolution", "--troughs", "--seed",
                                "--ellipsoid", "--craters", "--threads", "--out", "--grid"]),
    (["generate", "mars-strip"], ["--lat", "--lon", "--inclination", "--descending",
                                  "--length-km", "--width-km", "--resolution", "--ragged",
                                  "--seed", "--ellipsoid", "--craters", "--out", "--grid"]),
    (["generate", "mars-planet"], ["--seed", "--size", "--resolution", "--out", "--patch",
                                   "--deflate", "--levels", "--ellipsoid", "--craters"]),
    (["generate", "victoria"], ["--seed", "--size", "--resolution", "--out", "--patch",
                                "--deflate"]),
    (["info"], ["--json", "file", "raster", "Example"]),
    (["import"], ["source", "--out", "--grid", "--patch", "--levels", "--deflate", "--threads",
                  "--nodata", "tiles", "Example"]),
    (["query"], ["--grid", "--interp", "--coords", "--cache-mb", "--frame", "nan", "valid",
                "Example"]),
    (["walkthrough"], ["--size", "--spacing", "--queries", "--out"]),
    (["demo"], ["--out", "--data", "--cache-mb", "--frames", "--quick"]),
    (["render"], ["--target", "--distance", "--heading", "--elevation", "--fov", "--out",
                 "Example"]),
])
def test_help(cmd, expect):
    p = run(*cmd, "--help")
    assert p.returncode == 0
    assert "Usage" in p.stdout or "USAGE" in p.stdout.upper()
    for word in expect:
        assert word in p.stdout, (cmd, word)


@pytest.mark.parametrize("args,needle", [
    ([], "subcommand"),
    (["generate"], "subcommand"),
    (["frobnicate"], "subcommand"),
    (["query", "x.h5", "--interp", "cubic"], "cubic"),
    (["generate", "victoria"], "--out"),
    (["generate", "victoria", "--out", "x.h5", "--deflate", "12"], "deflate"),
    (["generate", "mars-cap", "--out", "x.h5", "--pole", "east"], "--pole"),
    (["generate", "mars-strip", "--out", "x.h5", "--ragged", "2"], "--ragged"),
    (["import", "x.tif"], "--out"),
    (["import", "--out", "x.h5"], "source"),
    (["import", "x.tif", "--out", "x.h5", "--patch", "4"], "patch"),
])
def test_usage_errors(args, needle):
    p = run(*args, check=False)
    assert p.returncode != 0
    assert p.stderr.startswith("regolith: error: "), p.stderr
    assert needle in p.stderr
    assert p.stdout == ""
    # The hint names the subcommand that failed.
    words = [a for a in args
             if a in ("generate", "victoria", "mars-cap", "mars-strip", "query", "import")]
    assert f"Run '{' '.join(['regolith', *words])} --help'" in p.stderr, p.stderr


# ---- generate -------------------------------------------------------------------------------

def test_generate_is_deterministic(work, victoria):
    again = work / "victoria-again.h5"
    other = work / "victoria-other.h5"
    run("generate", "victoria", "--out", again, "--size", 241, "--resolution", 5,
        "--patch", 100, "--seed", 3)
    run("generate", "victoria", "--out", other, "--size", 241, "--resolution", 5,
        "--patch", 64, "--seed", 4)
    a, b, c = level0(victoria, "victoria"), level0(again, "victoria"), level0(other, "victoria")
    assert np.array_equal(a, b)  # a different patch size changes no sample
    assert np.mean(a != c) > 0.9


def test_generate_planet_options(work):
    path = work / "ell.h5"
    run("generate", "mars-planet", "--out", path, "--resolution", 4.5, "--ellipsoid",
        "--craters", 0, "--grid", "red", "--levels", 2)
    a = attrs(path, "red")
    assert a["rows"] == 40 and a["cols"] == 80
    assert a["polar_radius"] == 3376200.0 and a["levels"] == 2
    assert a["latitude_type"] == "planetocentric"
    p = run("generate", "mars-planet", "--out", work / "bad.h5", "--resolution", 7,
            check=False)
    assert p.returncode != 0 and p.stderr.startswith("regolith: error: ")
    assert "--resolution" in p.stderr
    assert not (work / "bad.h5").exists()


def crs_lonlat(srs_text, points):
    """PROJ (through GDAL's OSR) as the oracle: longitude, latitude of map points."""
    srs = osr.SpatialReference()
    if srs_text.startswith("+proj"):
        srs.ImportFromProj4(srs_text)
    else:
        srs.ImportFromWkt(srs_text)
    geo = srs.CloneGeogCS()
    for r in (srs, geo):
        r.SetAxisMappingStrategy(osr.OAMS_TRADITIONAL_GIS_ORDER)
    ct = osr.CoordinateTransformation(srs, geo)
    return [ct.TransformPoint(x, y)[:2] for x, y in points]


def test_generate_cap(work):
    path = work / "south.h5"
    p = run("generate", "mars-cap", "--out", path, "--pole", "south", "--min-lat", 70,
            "--resolution", 40000, "--troughs", 300, "--seed", 5, "--patch", 32)
    assert p.stdout == (f"Wrote {path}: polar stereographic DEM grid 'south_cap', "
                        "61 x 61 samples\n")
    a = attrs(path, "south_cap")
    assert a["kind"] == "dem" and a["placement"] == "polar_stereographic"
    assert a["pole"] == -1 and a["scale_factor"] == 1.0 and a["lon_centre_deg"] == 0.0
    # 2 R tan(10°) = 1197688 m from the pole to 70°S: 30 spacings of 40 km reach it.
    assert a["rows"] == a["cols"] == 61 and list(a["spacing"]) == [40000.0, 40000.0]
    assert a["x0"] == -a["y0"] == -1200000.0
    h = level0(path, "south_cap")
    assert np.isfinite(h).all()
    # Statistics are stored (format 1.3) and are numpy's.
    assert a["height_min"] == h.min() and a["height_max"] == h.max()
    # PROJ puts the edge midpoints at or beyond 70°S and one spacing inwards within it.
    stere = "+proj=stere +lat_0=-90 +lon_0=0 +k=1 +x_0=0 +y_0=0 +R=3396190 +units=m +no_defs"
    (_, edge), (_, inside) = crs_lonlat(stere, [(0.0, a["y0"]), (0.0, a["y0"] - 40000.0)])
    assert edge >= -70.0 - 1e-9 and inside < -70.0
    # The same seed again gives the same samples; another seed does not.
    again, other = work / "south-again.h5", work / "south-other.h5"
    run("generate", "mars-cap", "--out", again, "--pole", "south", "--min-lat", 70,
        "--resolution", 40000, "--troughs", 300, "--seed", 5, "--patch", 48, "--threads", 1)
    run("generate", "mars-cap", "--out", other, "--pole", "south", "--min-lat", 70,
        "--resolution", 40000, "--troughs", 300, "--seed", 6)
    assert np.array_equal(h, level0(again, "south_cap"))
    assert np.mean(h != level0(other, "south_cap")) > 0.9


def test_generate_strip(work):
    path = work / "strip.h5"
    p = run("generate", "mars-strip", "--out", path, "--lat", 20, "--lon", 30,
            "--inclination", 60, "--length-km", 100, "--width-km", 5, "--resolution", 250,
            "--grid", "lroc", "--patch", 64)
    assert p.stdout == f"Wrote {path}: oblique Mercator DEM grid 'lroc', 21 x 401 samples\n"
    a = attrs(path, "lroc")
    assert a["kind"] == "dem" and a["placement"] == "projected"
    assert "Hotine Oblique Mercator (variant B)" in a["crs_wkt"]
    assert a["x0"] == -50000.0 and a["y0"] == 2500.0
    h = level0(path, "lroc")
    missing = np.isnan(h)
    assert missing.any() and missing.mean() < 0.25  # ragged edges, not a ragged strip
    assert not missing[8:13, 20:-20].any()           # the core is covered
    assert a["valid_samples"] == int((~missing).sum())
    # PROJ (OSR) reads the stored CRS: the grid's centre is the strip's centre, and 50 km
    # along the track (+x) lies north-east (an ascending pass inclined 60°: azimuth
    # asin(cos 60° / cos 20°) = 32.2°).
    (lon0, lat0), (lon1, lat1) = crs_lonlat(a["crs_wkt"], [(0.0, 0.0), (50000.0, 0.0)])
    assert lon0 == pytest.approx(30.0, abs=1e-9) and lat0 == pytest.approx(20.0, abs=1e-9)
    dn = math.radians(lat1 - lat0)
    de = math.radians(lon1 - lon0) * math.cos(math.radians(lat0))
    azimuth = math.degrees(math.atan2(de, dn))
    assert azimuth == pytest.approx(math.degrees(math.asin(0.5 / math.cos(math.radians(20)))),
                                    abs=0.2)
    # --ragged 0: every sample valid.
    full = work / "strip-full.h5"
    run("generate", "mars-strip", "--out", full, "--lat", 20, "--lon", 30, "--length-km", 100,
        "--width-km", 5, "--resolution", 250, "--ragged", 0)
    assert np.isfinite(level0(full, "strip")).all()


@pytest.mark.parametrize("args,message", [
    (["mars-strip", "--lat", 70],
     "store::StripGenerator(): centre latitude is 70 degrees, expected within the reach of an "
     "orbit inclined 60 degrees (|latitude| <= 60)"),
    (["mars-cap", "--min-lat", 90],
     "store::PolarCapGenerator(): minimum latitude is 90 degrees, expected > 0 and < 90"),
])
def test_generate_cap_and_strip_refuse_bad_options(work, args, message):
    out = work / "refused.h5"
    p = run("generate", *args, "--out", out, check=False)
    assert p.returncode != 0
    assert p.stderr == f"regolith: error: {message}\n"
    assert p.stdout == ""
    assert not out.exists()


def test_generate_into_a_missing_folder(work):
    p = run("generate", "victoria", "--out", work / "no" / "such" / "v.h5", check=False)
    assert p.returncode != 0
    assert p.stderr == (f"regolith: error: generate victoria: --out {work / 'no' / 'such' / 'v.h5'}:"
                        f" folder {work / 'no' / 'such'} does not exist\n")


def test_generate_progress_only_on_a_terminal(work):
    master, slave = pty.openpty()
    try:
        p = subprocess.Popen([BIN, "generate", "mars-planet", "--out", work / "tty.h5",
                              "--size", "64", "--patch", "16"], stdout=subprocess.PIPE,
                             stderr=slave)
        os.close(slave)
        slave = -1
        seen = b""
        while True:
            ready, _, _ = select.select([master], [], [], 60)
            if not ready:
                break
            try:
                chunk = os.read(master, 4096)
            except OSError:
                break
            if not chunk:
                break
            seen += chunk
        p.wait(timeout=60)
        assert p.returncode == 0
    finally:
        os.close(master)
        if slave >= 0:
            os.close(slave)
    text = seen.decode()
    assert "100%" in text and "[" in text and "\r" in text


def test_generate_interrupted_leaves_no_file(work):
    import signal
    import time
    out = work / "interrupted.h5"
    p = subprocess.Popen([BIN, "generate", "mars-planet", "--out", str(out), "--size", "4096",
                          "--threads", "1"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                         text=True)
    tmps = f"interrupted.h5.tmp-{p.pid}-*"  # core::writeFileAtomically's temporary
    deadline = time.monotonic() + 120
    while not list(work.glob(tmps)) and p.poll() is None and time.monotonic() < deadline:
        time.sleep(0.01)
    assert list(work.glob(tmps)), "the write never started"
    p.send_signal(signal.SIGINT)
    _, err = p.communicate(timeout=120)
    assert p.returncode != 0
    assert err.startswith("regolith: error: ") and "cancelled" in err, err
    assert not out.exists() and not list(work.glob(tmps))


# ---- info -----------------------------------------------------------------------------------

def check_info_against_h5py(path, info):
    with h5py.File(path, "r") as f:
        assert info["format_version"] == [int(v) for v in f.attrs["format_version"]]
        names = sorted(f["grids"].keys())
        assert [g["name"] for g in info["grids"]] == names
        for g in info["grids"]:
            h = f["grids"][g["name"]]
            a = plain_attrs(h)
            assert g["kind"] == a["kind"]
            assert g["rows"] == int(a["rows"]) and g["cols"] == int(a["cols"])
            assert g["x0"] == float(a["x0"]) and g["y0"] == float(a["y0"])
            assert g["spacing"] == [float(v) for v in a["spacing"]]
            dx, dy = (float(v) for v in a["spacing"])
            assert g["extent"] == {"west": float(a["x0"]) - dx / 2,
                                   "east": float(a["x0"]) + (int(a["cols"]) - 0.5) * dx,
                                   "north": float(a["y0"]) + dy / 2,
                                   "south": float(a["y0"]) - (int(a["rows"]) - 0.5) * dy}
            assert g["units"] == a["units"]
            assert g["body"] == {"name": a["body"],
                                 "equatorial_radius": float(a["equatorial_radius"]),
                                 "polar_radius": float(a["polar_radius"])}
            assert g["latitude_type"] == a["latitude_type"]
            assert g["levels"] == int(a["levels"])
            assert g["patch_shape"] == [int(v) for v in a["patch_shape"]]
            nodata = float(a["nodata"]) if "nodata" in a else math.nan
            assert (g["nodata"] is None) == math.isnan(nodata)
            if g["nodata"] is not None:
                assert g["nodata"] == nodata
            assert g["scale"] == float(a["scale"]) and g["offset"] == float(a["offset"])
            tiled = "tiles" in h
            assert g["tiled"] == tiled
            if "valid_samples" in a:  # format 1.3: stored at import
                assert g["statistics"] == {"min": float(a["height_min"]),
                                           "max": float(a["height_max"]),
                                           "mean": float(a["height_mean"]),
                                           "valid_samples": int(a["valid_samples"])}
            else:
                assert g["statistics"] is None
            if "provenance" in a:  # format 1.3: recorded at import
                assert g["provenance"] == json.loads(a["provenance"])
            else:
                assert g["provenance"] is None
            for k, shape in enumerate(g["level_shapes"]):
                if k == 0 and tiled:
                    assert shape == [g["rows"], g["cols"]]
                else:
                    assert list(h[f"level{k}"].shape) == shape
            if a["kind"] == "planet":
                assert g["placement"] is None
            else:
                p = g["placement"]
                assert p["kind"] == a["placement"]
                for key, value in p.items():
                    if key == "kind":
                        continue
                    if value is None:
                        assert key not in a
                    else:
                        assert value == float(a[key]), key


def test_info_json_matches_h5py(victoria, planet, h5py_store, fixture_stores):
    for path in [victoria, planet, h5py_store[0], *fixture_stores]:
        p = run("info", path, "--json")
        info = json.loads(p.stdout)
        assert info["path"] == str(path)
        check_info_against_h5py(path, info)
    info = json.loads(run("info", fixture_stores[1], "--json").stdout)
    assert any(g["tiled"] for g in info["grids"])  # the tiled fixture is reported as tiled
    assert info["format_version"] == [1, 4]


def test_info_text(victoria, planet):
    text = run("info", victoria).stdout
    for needle in ["grid 'victoria'", "241 rows x 241 cols", "5 x 5 m", "local_tangent_plane",
                   "origin lat -2.05 deg, lon -5.5 deg", "planetodetic", "tiled:          no",
                   "nodata:         none", "patch:          64 x 64", "format version: 1.4"]:
        assert needle in text, needle
    text = run("info", planet).stdout
    for needle in ["grid 'mars'", "60 rows x 120 cols", "3 x 3 deg", "planetocentric",
                   "lon -180 to 180, lat -90 to 90 deg"]:
        assert needle in text, needle


def test_info_errors(work):
    p = run("info", work / "missing.h5", check=False)
    assert p.returncode != 0 and p.stderr.startswith("regolith: error: ")
    assert "missing.h5" in p.stderr and "no such file" in p.stderr
    junk = work / "junk.h5"
    junk.write_bytes(b"not an hdf5 file at all")
    p = run("info", junk, "--json", check=False)
    assert p.returncode != 0 and "junk.h5" in p.stderr and "not an HDF5 file" in p.stderr
    assert p.stdout == ""


# ---- import and info on rasters --------------------------------------------------------------

def store_heights(path, grid, level=0):
    """Heights of a level as docs/store-format.md says to read them (NaN where missing), with
    tiled level 0 assembled from its internal tiles."""
    with h5py.File(path, "r") as f:
        g = f[f"grids/{grid}"]
        a = g.attrs
        nodata = float(a.get("nodata", np.nan))

        def decode(x):
            x = x.astype(np.float64)
            x[np.isnan(x) | (x == nodata)] = np.nan
            return float(a["offset"]) + float(a["scale"]) * x

        if level > 0 or "tile_count" not in a:
            return decode(g[f"level{level}"][...])
        out = np.full((int(a["rows"]), int(a["cols"])), np.nan)
        for i in range(int(a["tile_count"])):
            t = g[f"tiles/{i}"]
            assert "external_file" not in t.attrs  # an import copies its tiles
            r0, c0 = int(t.attrs["row0"]), int(t.attrs["col0"])
            tile = decode(t["level0"][...])
            out[r0:r0 + tile.shape[0], c0:c0 + tile.shape[1]] = tile
        return out


def gdal_heights(path, void_marker=False):
    """GDAL's samples after scale/offset, NaN where GDAL's nodata (or -32768 in a file that
    declares no nodata, docs/import.md) says missing."""
    ds = gdal.Open(str(path))
    band = ds.GetRasterBand(1)
    v = band.ReadAsArray().astype(np.float64)
    missing = np.isnan(v)
    nodata = band.GetNoDataValue()
    if nodata is not None:
        missing |= v == nodata
    elif void_marker:
        missing |= v == -32768
    v = (band.GetOffset() or 0.0) + (band.GetScale() or 1.0) * v
    v[missing] = np.nan
    return v


def short(v):
    """Python's shortest round-trip text of a double, as the command prints it."""
    text = repr(float(v))
    return text[:-2] if text.endswith(".0") else text


def summary_field(stdout, name):
    for line in stdout.splitlines():
        if line.strip().startswith(name + ":"):
            return line.split(":", 1)[1].strip()
    raise AssertionError(f"no '{name}:' line in\n{stdout}")


@pytest.mark.parametrize("compression", [["--deflate", 3], ["--compression", "zfp"]],
                         ids=["deflate", "zfp"])
@pytest.mark.parametrize("name,grid,kind,void_marker", [
    ("Shoemaker_1k.tif", "Shoemaker_1k", "dem", False),
    ("S11E119.hgt", "S11E119", "planet", False),
    ("dem_unfinished.tif", "dem_unfinished", "planet", True),
    ("dem_nodata.dem", "dem_nodata", "dem", False),  # NAD27 / UTM zone 10N
])
def test_import_matches_gdal(work, name, grid, kind, void_marker, compression):
    src = dem_fixture(name)
    out = work / f"imported-{grid}-{compression[-1]}.h5"
    p = run("import", src, "--out", out, "--patch", 64, *compression)
    with h5py.File(out, "r") as f:  # the codec asked for is the one HDF5 records
        plist = f[f"grids/{grid}/level0"].id.get_create_plist()
        ids = [plist.get_filter(i)[0] for i in range(plist.get_nfilters())]
        assert ids == ([32013] if "zfp" in compression else [2, 1])  # H5Z-ZFP; shuffle, deflate
    assert p.stderr == ""  # no progress bar: stderr is not a terminal
    expected = gdal_heights(src, void_marker)
    got = store_heights(out, grid)
    assert got.shape == expected.shape
    assert np.array_equal(np.isnan(got), np.isnan(expected))
    # Stored as float32: the source values (int16 or float32 here) survive exactly.
    ok = ~np.isnan(expected)
    assert np.array_equal(got[ok], expected[ok].astype(np.float32).astype(np.float64))
    # The summary agrees with GDAL and with the file.
    ds = gdal.Open(src)
    out_text = p.stdout
    assert out_text.startswith(f"Wrote {out} from 1 file\n")
    assert summary_field(out_text, "grid").startswith(f"'{grid}', {kind}")
    assert summary_field(out_text, "size") == f"{ds.RasterYSize} rows x {ds.RasterXSize} cols"
    assert summary_field(out_text, "driver") == ds.GetDriver().ShortName
    assert summary_field(out_text, "missing").startswith(f"{int(np.isnan(expected).sum())} "
                                                         "samples")
    assert summary_field(out_text, "tiles") == "1"
    float(summary_field(out_text, "seconds"))
    a = attrs(out, grid)
    assert a["kind"] == kind
    srs = ds.GetSpatialRef()
    assert float(a["equatorial_radius"]) == pytest.approx(srs.GetSemiMajor(), abs=1e-6)
    assert summary_field(out_text, "body") == (
        f"{a['body']}, equatorial radius {short(a['equatorial_radius'])} m, polar radius "
        f"{short(a['polar_radius'])} m")
    assert summary_field(out_text, "latitude type") == str(a["latitude_type"])
    corrections = summary_field(out_text, "corrections")
    assert ("-32768 taken as missing" in corrections) == void_marker
    if not void_marker:
        assert corrections == "none"


def test_zfp_without_its_plugin_is_a_clear_error(work):
    # HDF5_PLUGIN_PATH replaces HDF5's plugin directories: here, with none that has H5Z-ZFP.
    store = work / "victoria-zfp.h5"
    run("generate", "victoria", "--out", store, "--size", 200, "--compression", "zfp")
    q = run("query", store, "--coords", "grid", "10,10")  # readable with the plugin
    assert parse_csv(q.stdout)[1][0][6:] == [1.0, 1.0, "ok"]
    env = {**os.environ, "HDF5_PLUGIN_PATH": str(work / "no-plugins-here")}

    def without_plugin(*args):
        return subprocess.run([BIN, *map(str, args)], capture_output=True, text=True,
                              timeout=120, env=env)

    for args in (["info", store], ["query", store, "--coords", "grid", "10,10"]):
        p = without_plugin(*args)
        assert p.returncode != 0, args
        assert "32013" in p.stderr and "hdf5-filter-plugin-zfp-serial" in p.stderr, p.stderr
        assert str(work / "no-plugins-here") in p.stderr  # where HDF5 looked
    out = work / "zfp-refused.h5"
    p = without_plugin("generate", "victoria", "--out", out, "--size", 100, "--compression", "zfp")
    assert p.returncode != 0 and "hdf5-filter-plugin-zfp-serial" in p.stderr, p.stderr
    assert not out.exists() and not list(work.glob("zfp-refused.h5.tmp*"))
    # Bad choices are named.
    p = run("generate", "victoria", "--out", out, "--size", 100, "--compression", "lz4",
            check=False)
    assert p.returncode != 0 and "lz4" in p.stderr
    p = run("generate", "victoria", "--out", out, "--size", 100, "--compression", "zfp",
            "--deflate", 4, check=False)
    assert p.returncode != 0 and "deflate level 4 with the zfp codec" in p.stderr, p.stderr
    assert not out.exists()


def test_import_options_and_corrections(work):
    out = work / "mola.h5"
    p = run("import", dem_fixture("megt90n000cb.lbl"), "--out", out, "--grid", "mola",
            "--levels", 2, "--patch", 128, "--threads", 1)
    a = attrs(out, "mola")
    assert int(a["levels"]) == 2 and [int(v) for v in a["patch_shape"]] == [128, 128]
    assert summary_field(p.stdout, "levels") == "2, patch 128 x 128"
    # The MOLA label's two known traps (fixtures README): both corrections are reported.
    assert "PDS3 projection offsets" in p.stdout and "snapped" in p.stdout
    assert float(a["x0"]) == 0.125 and float(a["y0"]) == 89.875
    # --nodata: a further source value taken as missing.
    out2 = work / "mola-nodata.h5"
    src = gdal_heights(dem_fixture("megt90n000cb.lbl"))
    value = float(np.nanmin(src))
    p = run("import", dem_fixture("megt90n000cb.lbl"), "--out", out2, "--nodata", value)
    got = store_heights(out2, "megt90n000cb")
    assert np.array_equal(np.isnan(got), src == value)
    assert summary_field(p.stdout, "missing").startswith(f"{int((src == value).sum())} samples")
    # Radii become heights (LOLA): the radius reference is reported.
    p = run("import", dem_fixture("ldem_4_reduced.cub"), "--out", work / "lola.h5")
    assert "1737400 m subtracted" in p.stdout
    lola = gdal_heights(dem_fixture("ldem_4_reduced.cub")) - 1737400.0
    assert np.allclose(store_heights(work / "lola.h5", "ldem_4_reduced"), lola, rtol=0,
                       atol=1e-3)


def cut_tiles(src, folder, row_cuts, col_cuts):
    """Cuts src into GeoTIFF tiles at the given row/col boundaries with gdal.Translate."""
    ds = gdal.Open(str(src))
    rows = [0, *row_cuts, ds.RasterYSize]
    cols = [0, *col_cuts, ds.RasterXSize]
    tiles = []
    for i in range(len(rows) - 1):
        for j in range(len(cols) - 1):
            path = folder / f"tile-{i}-{j}.tif"
            gdal.Translate(str(path), ds, srcWin=[cols[j], rows[i], cols[j + 1] - cols[j],
                                                  rows[i + 1] - rows[i]])
            tiles.append(path)
    return tiles


def test_import_tiles_equals_the_single_import(work):
    folder = work / "tiles"
    folder.mkdir()
    src = dem_fixture("Shoemaker_1k.tif")
    tiles = cut_tiles(src, folder, [100], [37, 200])
    single = work / "shoemaker-single.h5"
    mosaic = work / "shoemaker-tiles.h5"
    run("import", src, "--out", single, "--patch", 32, "--grid", "s")
    p = run("import", *reversed(tiles), "--out", mosaic, "--patch", 32, "--grid", "s")
    assert p.stdout.startswith(f"Wrote {mosaic} from 6 files\n")
    assert summary_field(p.stdout, "tiles") == "6"
    assert "tiled" in summary_field(p.stdout, "grid")
    a, b = attrs(single, "s"), attrs(mosaic, "s")
    assert int(b["tile_count"]) == 6
    for key in ["rows", "cols", "x0", "y0", "spacing", "levels", "kind", "placement"]:
        assert np.array_equal(a[key], b[key]), key
    one, many = store_heights(single, "s"), store_heights(mosaic, "s")
    assert np.array_equal(one, many, equal_nan=True)
    assert np.array_equal(one, gdal_heights(src), equal_nan=True)
    # Missing samples are counted across tiles as for the whole file...
    assert summary_field(p.stdout, "missing").startswith(f"{int(np.isnan(one).sum())} samples")
    # ... and a gap (a tile left out) counts as missing: h5py's count of NaN is the oracle.
    gappy = work / "shoemaker-gap.h5"
    p = run("import", *tiles[:4], *tiles[5:], "--out", gappy, "--patch", 32, "--grid", "s")
    with_gap = store_heights(gappy, "s")
    assert with_gap.shape == one.shape  # the left-out tile is not on the mosaic's border
    assert summary_field(p.stdout, "missing").startswith(
        f"{int(np.isnan(with_gap).sum())} samples"), p.stdout
    assert "gaps between tiles included" in summary_field(p.stdout, "missing")
    # The pyramid levels are built across tile borders, as for the whole file.
    for k in range(1, int(a["levels"])):
        assert np.array_equal(store_heights(single, "s", k), store_heights(mosaic, "s", k),
                              equal_nan=True), k
    # Overlapping tiles are refused, naming the tile.
    overlap = folder / "overlap.tif"
    gdal.Translate(str(overlap), gdal.Open(src), srcWin=[30, 90, 20, 20])
    bad = work / "overlap.h5"
    p = run("import", tiles[0], overlap, "--out", bad, check=False)
    assert p.returncode != 0 and p.stdout == "" and not bad.exists()
    assert str(overlap) in p.stderr and "overlaps" in p.stderr


def test_info_on_a_raster(work):
    src = dem_fixture("Shoemaker_1k.tif")
    ds = gdal.Open(src)
    srs = ds.GetSpatialRef()
    gt = ds.GetGeoTransform()
    info = json.loads(run("info", src, "--json").stdout)
    assert info["path"] == src
    r = info["raster"]
    assert r["driver"] == "GTiff"
    assert srs.GetAttrValue("PROJECTION") in r["projection"]
    assert r["radius_reference"] == 0.0 and r["corrections"] == []
    assert not (r["offset_corrected"] or r["spacing_snapped"] or r["void_marker_assumed"])
    g = info["grid"]
    assert g["kind"] == "dem" and g["name"] == "Shoemaker_1k"
    assert (g["rows"], g["cols"]) == (ds.RasterYSize, ds.RasterXSize)
    assert g["spacing"] == [gt[1], -gt[5]]
    # Sample (0, 0) is the pixel centre (docs/grid-convention.md).
    assert g["x0"] == pytest.approx(gt[0] + gt[1] / 2, abs=1e-9)
    assert g["y0"] == pytest.approx(gt[3] + gt[5] / 2, abs=1e-9)
    assert g["body"]["equatorial_radius"] == srs.GetSemiMajor()
    assert g["placement"]["kind"] == "polar_stereographic" and g["placement"]["pole"] == -1
    assert "levels" not in g and "tiled" not in g  # nothing is stored yet
    # The store an import writes has the same grid.
    out = work / "info-raster.h5"
    run("import", src, "--out", out)
    stored = json.loads(run("info", out, "--json").stdout)["grids"][0]
    for key, value in g.items():
        assert stored[key] == value, key
    # Human-readable, with the corrections of a global ISIS cube.
    text = run("info", src).stdout
    assert text.startswith(f"raster:         {src} (not a store")
    assert "driver:         GTiff" in text and "Polar_Stereographic" in text
    assert "grid 'Shoemaker_1k'" in text and "256 rows x 256 cols" in text
    text = run("info", dem_fixture("ldem_4_reduced.cub")).stdout
    assert "driver:         ISIS3" in text and "1737400 m subtracted" in text
    info = json.loads(run("info", dem_fixture("ldem_4_reduced.cub"), "--json").stdout)
    assert info["raster"]["radius_reference"] == 1737400.0
    assert info["raster"]["spacing_snapped"] is True
    assert info["grid"]["kind"] == "planet"


def test_import_drops_padding_beyond_a_pole_and_info_reads_gdal_virtual_paths(work):
    # A global geographic grid of 181 rows of 1 deg: row 0 is centred at 90.5 deg N and
    # wholly missing (ISIS-style padding). The import drops it and says so.
    path = work / "padded.tif"
    ds = gdal.GetDriverByName("GTiff").Create(str(path), 360, 181, 1, gdal.GDT_Float32)
    srs = osr.SpatialReference()
    srs.ImportFromProj4("+proj=longlat +R=1737400 +no_defs")
    ds.SetProjection(srs.ExportToWkt())
    ds.SetGeoTransform([-180.0, 1.0, 0.0, 91.0, 0.0, -1.0])
    values = np.arange(181 * 360, dtype=np.float32).reshape(181, 360)
    values[0, :] = -9999.0
    ds.GetRasterBand(1).SetNoDataValue(-9999.0)
    ds.GetRasterBand(1).WriteArray(values)
    ds = None
    info = json.loads(run("info", path, "--json").stdout)
    assert info["raster"]["dropped_north_rows"] == 1
    assert info["raster"]["dropped_south_rows"] == 0
    assert info["grid"]["rows"] == 180 and info["grid"]["y0"] == 89.5
    out = work / "padded.h5"
    p = run("import", path, "--out", out)
    assert summary_field(p.stdout, "corrections") == (
        "wholly missing rows beyond a pole dropped: 1 north, 0 south")
    assert np.array_equal(store_heights(out, "padded"), gdal_heights(path)[1:, :])
    # The store opens and answers at GDAL's pixel centres (row 1 of the source is row 0).
    q = parse_csv(run("query", out, "--coords", "lonlat", "--interp", "nearest",
                      "180.5,89.5", "0.5,0.5").stdout)[1]
    assert [row[2] for row in q] == [float(values[1, 0]), float(values[90, 180])]
    # No -32768 note for an int16 source that declares no nodata but has no such value.
    clean = work / "int16-no-voids.tif"
    ds = gdal.GetDriverByName("GTiff").Create(str(clean), 8, 6, 1, gdal.GDT_Int16)
    ds.SetProjection(srs.ExportToWkt())
    ds.SetGeoTransform([10.0, 1.0, 0.0, 20.0, 0.0, -1.0])
    ds.GetRasterBand(1).WriteArray(np.arange(48, dtype=np.int16).reshape(6, 8))
    ds = None
    p = run("import", clean, "--out", work / "int16-no-voids.h5")
    assert summary_field(p.stdout, "corrections") == "none"
    # info and import take GDAL's virtual paths, as GDAL does.
    archive = work / "fixture.zip"
    with zipfile.ZipFile(archive, "w") as z:
        z.write(dem_fixture("Shoemaker_1k.tif"), "Shoemaker_1k.tif")
    vsi = f"/vsizip/{archive}/Shoemaker_1k.tif"
    zipped = json.loads(run("info", vsi, "--json").stdout)
    plain = json.loads(run("info", dem_fixture("Shoemaker_1k.tif"), "--json").stdout)
    assert zipped["grid"] == plain["grid"] and zipped["raster"] == plain["raster"]
    run("import", vsi, "--out", work / "zipped.h5")
    assert np.array_equal(store_heights(work / "zipped.h5", "Shoemaker_1k"),
                          gdal_heights(dem_fixture("Shoemaker_1k.tif")), equal_nan=True)


def test_import_pds3_label_resolution_is_the_truth(work):
    # A PDS3 product written here (label text and MSB int16 image): the Moon at 2.5 px/deg,
    # MAP_SCALE rounded to 12.115 km (0.3995 deg), 451 lines whose last one is missing
    # padding beyond the south pole. Through the metres, 451 lines span 180.19 deg: the old
    # snap to 180/451 deg contradicted MAP_RESOLUTION. Offsets in MOLA's convention.
    rows, cols = 451, 900
    values = (np.arange(rows * cols) % 30000).astype(">i2").reshape(rows, cols)
    values[450, :] = -32768
    values.tofile(work / "pds3.img")
    (work / "pds3.lbl").write_text(f"""PDS_VERSION_ID = PDS3
RECORD_TYPE = FIXED_LENGTH
RECORD_BYTES = {cols * 2}
FILE_RECORDS = {rows}
^IMAGE = "pds3.img"
OBJECT = IMAGE
  LINES = {rows}
  LINE_SAMPLES = {cols}
  SAMPLE_TYPE = MSB_INTEGER
  SAMPLE_BITS = 16
  MISSING_CONSTANT = -32768
  UNIT = METER
END_OBJECT = IMAGE
OBJECT = IMAGE_MAP_PROJECTION
  MAP_PROJECTION_TYPE = "SIMPLE CYLINDRICAL"
  A_AXIS_RADIUS = 1737.4 <KM>
  B_AXIS_RADIUS = 1737.4 <KM>
  C_AXIS_RADIUS = 1737.4 <KM>
  POSITIVE_LONGITUDE_DIRECTION = EAST
  CENTER_LATITUDE = 0.0 <DEGREE>
  CENTER_LONGITUDE = 180.0 <DEGREE>
  MAP_RESOLUTION = 2.5 <PIXEL/DEGREE>
  MAP_SCALE = 12.115 <KM/PIXEL>
  LINE_PROJECTION_OFFSET = 225.5
  SAMPLE_PROJECTION_OFFSET = 450.5
  COORDINATE_SYSTEM_NAME = PLANETOCENTRIC
END_OBJECT = IMAGE_MAP_PROJECTION
END
""")
    out = work / "pds3.h5"
    p = run("import", work / "pds3.lbl", "--out", out, "--grid", "pds3")
    corrections = p.stdout.split("corrections:", 1)[1]
    assert "PDS3 projection offsets read in the other convention" in corrections
    assert "global spacing snapped to the label's resolution" in corrections
    assert "wholly missing rows beyond a pole dropped: 0 north, 1 south" in corrections
    a = attrs(out, "pds3")
    assert a["kind"] == "planet" and [float(v) for v in a["spacing"]] == [0.4, 0.4]
    assert int(a["rows"]) == 450 and int(a["cols"]) == 900
    assert float(a["x0"]) == pytest.approx(0.2, abs=1e-12)
    assert float(a["y0"]) == pytest.approx(89.8, abs=1e-12)
    assert np.array_equal(store_heights(out, "pds3"), values[:450, :].astype(np.float64))
    # Nearest queries at the label's sample centres return those samples (1 um: in the
    # outermost rows TopoPlanet's polar cap may see a centre an ulp poleward and blend).
    pts = [(0, 0), (0, 899), (224, 450), (449, 0), (449, 899), (300, 613)]
    args = [f"{0.2 + 0.4 * c!r},{89.8 - 0.4 * r!r}" for r, c in pts]
    q = parse_csv(run("query", out, "--coords", "lonlat", "--interp", "nearest", *args).stdout)[1]
    assert [row[2] for row in q] == pytest.approx([float(values[r, c]) for r, c in pts],
                                                  rel=0, abs=1e-6)


def test_import_window_bbox_and_body(work):
    src = dem_fixture("megt90n000cb.lbl")
    full = json.loads(run("info", src, "--json").stdout)["grid"]
    out = work / "window.h5"
    p = run("import", src, "--out", out, "--window", "100,200,50,60", "--body", "Mars")
    assert summary_field(p.stdout, "size") == "50 rows x 60 cols (window from row 100, col 200)"
    assert summary_field(p.stdout, "body").startswith("Mars,")
    a = attrs(out, "megt90n000cb")
    assert a["body"] == "Mars"
    assert float(a["x0"]) == full["x0"] + 200 * full["spacing"][0]
    assert float(a["y0"]) == full["y0"] - 100 * full["spacing"][1]
    # GDAL's reading of the MOLA label in the corrected offset convention (docs/import.md).
    keys = ("PDS_SampleProjOffset_Shift", "PDS_LineProjOffset_Shift")
    try:
        for k in keys:
            gdal.SetConfigOption(k, "-0.5")
        expected = gdal_heights(src)[100:150, 200:260]
    finally:
        for k in keys:
            gdal.SetConfigOption(k, None)
    assert np.array_equal(store_heights(out, "megt90n000cb"), expected)
    # --bbox: the samples whose centres lie in the box.
    p = run("import", src, "--out", work / "bbox.h5", "--bbox", "137.0,-6.1,138.3,-5.0")
    b = attrs(work / "bbox.h5", "megt90n000cb")
    lons = float(b["x0"]) + np.arange(int(b["cols"])) * full["spacing"][0]
    lats = float(b["y0"]) - np.arange(int(b["rows"])) * full["spacing"][1]
    assert lons.min() >= 137.0 and lons.max() <= 138.3
    assert lats.min() >= -6.1 and lats.max() <= -5.0
    assert lons.min() - full["spacing"][0] < 137.0 and lons.max() + full["spacing"][0] > 138.3
    p = run("import", src, "--out", work / "both.h5", "--bbox", "1,2,3,4", "--window",
            "0,0,1,1", check=False)
    assert p.returncode != 0 and "excludes" in p.stderr


def test_info_statistics_corners_and_ground_size(work):
    src = dem_fixture("Shoemaker_1k.tif")  # south polar stereographic, NaN nodata
    out = work / "stats.h5"
    run("import", src, "--out", out)
    info = json.loads(run("info", out, "--json").stdout)
    assert info["format_version"] == [1, 4]
    g = info["grids"][0]
    check_info_against_h5py(out, info)
    # The statistics stored at import are numpy's over the stored level 0.
    h = store_heights(out, "Shoemaker_1k")
    st = g["statistics"]
    assert st["valid_samples"] == int(np.count_nonzero(~np.isnan(h)))
    assert st["min"] == float(np.nanmin(h)) and st["max"] == float(np.nanmax(h))
    assert st["mean"] == pytest.approx(float(np.nanmean(h)), rel=1e-12)
    # Corners and centre: OSR's longitude/latitude of GDAL's pixel centres.
    ds = gdal.Open(src)
    gt = ds.GetGeoTransform()
    srs = ds.GetSpatialRef()
    geo = srs.CloneGeogCS()
    for r in (srs, geo):
        r.SetAxisMappingStrategy(osr.OAMS_TRADITIONAL_GIS_ORDER)
    ct = osr.CoordinateTransformation(srs, geo)
    rows, cols = ds.RasterYSize, ds.RasterXSize

    def lonlat(r, c):
        return ct.TransformPoint(gt[0] + (c + 0.5) * gt[1], gt[3] + (r + 0.5) * gt[5])[:2]

    for key, (r, c) in {"north_west": (0, 0), "north_east": (0, cols - 1),
                        "south_west": (rows - 1, 0), "south_east": (rows - 1, cols - 1),
                        "centre": ((rows - 1) / 2, (cols - 1) / 2)}.items():
        lon, lat = lonlat(r, c)
        assert g["geodetic"][key]["lat"] == pytest.approx(lat, abs=1e-9), key
        assert math.remainder(g["geodetic"][key]["lon"] - lon, 360.0) == pytest.approx(0, abs=1e-9)
    # Ground size: the centre row and column, pixel edge to edge, as 256-segment polylines of
    # OSR's points on the sphere.
    radius = srs.GetSemiMajor()
    assert srs.GetSemiMinor() == radius

    def polyline(points):
        lon, lat = np.radians(np.array(points)).T
        xyz = radius * np.column_stack([np.cos(lat) * np.cos(lon), np.cos(lat) * np.sin(lon),
                                        np.sin(lat)])
        return float(np.linalg.norm(np.diff(xyz, axis=0), axis=1).sum())

    t = np.linspace(0.0, 1.0, 257)
    mid_r, mid_c = (rows - 1) / 2, (cols - 1) / 2
    width = polyline([lonlat(mid_r, -0.5 + k * cols) for k in t])
    height = polyline([lonlat(-0.5 + k * rows, mid_c) for k in t])
    assert g["ground_size_m"] == pytest.approx([width, height], rel=1e-9)
    text = run("info", out).stdout
    assert (f"  heights:        min {short(st['min'])}, max {short(st['max'])}, mean "
            f"{short(st['mean'])} m; {st['valid_samples']} valid samples") in text
    assert "  ground size:    " in text and "  corners:        NW " in text
    # Provenance: the source, its size and SHA-256 (hashlib's), GDAL's driver and version.
    prov = g["provenance"]
    with open(src, "rb") as fh:
        data = fh.read()
    assert [(s["file"], s["bytes"], s["sha256"]) for s in prov["sources"]] == [
        ("Shoemaker_1k.tif", len(data), hashlib.sha256(data).hexdigest())]
    assert prov["gdal_driver"] == "GTiff"
    assert prov["gdal_version"] == gdal.VersionInfo("RELEASE_NAME")
    assert prov["geotransform"] == list(gt)
    assert (f"  sources:        Shoemaker_1k.tif, {len(data)} bytes, sha256 "
            f"{hashlib.sha256(data).hexdigest()}\n") in text
    assert f"  made with:      GDAL {gdal.VersionInfo('RELEASE_NAME')}, driver GTiff\n" in text
    # An import told not to digest its sources (ImportOptions::digestSources, as regolith-mpi's
    # parts) records sizes only: a copy of the store with the digest taken out of its
    # provenance says so.
    bare = work / "no-digest.h5"
    bare.write_bytes(out.read_bytes())
    with h5py.File(bare, "r+") as f:
        grid = f["grids"][g["name"]]
        p = json.loads(grid.attrs["provenance"])
        del p["sources"][0]["sha256"]
        grid.attrs["provenance"] = json.dumps(p)
    assert (f"  sources:        Shoemaker_1k.tif, {len(data)} bytes, no digest recorded\n"
            in run("info", bare).stdout)
    # A store written without statistics (before format 1.3) still opens, and says so.
    old = work / "no-stats.h5"
    run("generate", "victoria", "--out", old, "--size", 64)
    assert json.loads(run("info", old, "--json").stdout)["grids"][0]["statistics"] is None
    old_text = run("info", old).stdout
    assert "no statistics stored (written before format 1.3)" in old_text
    assert "  provenance:     not recorded\n" in old_text
    assert json.loads(run("info", old, "--json").stdout)["grids"][0]["provenance"] is None


def orthographic_off_the_map_tif(path):
    """An orthographic grid centred beyond the horizon: no sample has a place on the body."""
    ds = gdal.GetDriverByName("GTiff").Create(str(path), 20, 10, 1, gdal.GDT_Float32)
    srs = osr.SpatialReference()
    srs.ImportFromProj4("+proj=ortho +lat_0=0 +lon_0=0 +R=3396190 +units=m +no_defs")
    ds.SetProjection(srs.ExportToWkt())
    ds.SetGeoTransform([5.0e6, 100.0, 0.0, 5000.0, 0.0, -100.0])
    ds.GetRasterBand(1).WriteArray(np.ones((10, 20), dtype=np.float32))
    ds = None


def wide_geotiff(path, rows, cols):
    """A float32 GeoTIFF on WGS84 longitude/latitude, smooth heights with a few voids."""
    y, x = np.mgrid[0:rows, 0:cols].astype(np.float64)
    h = (1000.0 * np.sin(x / 97.0) * np.cos(y / 53.0) + 0.37 * x).astype(np.float32)
    h[::37, ::41] = -9999.0
    ds = gdal.GetDriverByName("GTiff").Create(str(path), cols, rows, 1, gdal.GDT_Float32)
    ds.SetGeoTransform([10.0, 1e-4, 0.0, 5.0, 0.0, -1e-4])
    srs = osr.SpatialReference()
    srs.ImportFromEPSG(4326)
    ds.SetProjection(srs.ExportToWkt())
    band = ds.GetRasterBand(1)
    band.SetNoDataValue(-9999.0)
    band.WriteArray(h)
    ds = None


def test_import_memory_budget_tiles_the_pyramid_to_the_same_bits(work):
    src = work / "wide.tif"
    wide_geotiff(src, 300, 4096)
    whole, tiled = work / "wide-whole.h5", work / "wide-tiled.h5"
    p = run("import", src, "--out", whole, "--patch", 32, "--deflate", 2, "--grid", "w")
    assert summary_field(p.stdout, "memory budget").startswith(
        "1024 MiB (--memory-mb): whole-width bands, writer's buffers about ")
    rss = summary_field(p.stdout, "peak RSS")
    assert rss.endswith(" MiB (the whole process, GDAL's and HDF5's caches included)"), rss
    assert float(rss.split()[0]) > 1.0
    # Two bands of 32 x 4096 floats per level are about 4 MiB: 1 MiB tiles the pyramid.
    p = run("import", src, "--out", tiled, "--patch", 32, "--deflate", 2, "--grid", "w",
            "--memory-mb", 1)
    budget = summary_field(p.stdout, "memory budget")
    assert budget.startswith("1 MiB (--memory-mb): column tiles of "), budget
    assert " patches on " in budget, budget
    with h5py.File(whole, "r") as a, h5py.File(tiled, "r") as b:
        levels = int(a["grids/w"].attrs["levels"])
        assert levels == int(b["grids/w"].attrs["levels"]) > 5
        for k in range(levels):
            u, v = a[f"grids/w/level{k}"][...], b[f"grids/w/level{k}"][...]
            assert u.dtype == v.dtype == np.float32
            assert np.array_equal(u.view(np.uint32), v.view(np.uint32)), f"level {k}"
    assert np.array_equal(store_heights(tiled, "w"), gdal_heights(src), equal_nan=True)


def test_import_memory_budget_below_one_tile_is_refused(work):
    out = work / "too-small.h5"
    p = run("import", dem_fixture("Shoemaker_1k.tif"), "--out", out, "--patch", 1024,
            "--threads", 2, "--memory-mb", 60, check=False)
    assert p.returncode != 0
    # One 1024 x 1024 chunk is 4 MiB: a tile of one chunk read back (4) and encoded (5/4),
    # and 10 chunks of scratch for one thread: 15.25 chunks, 61 MiB.
    assert ("import: --memory-mb 60 is below the minimum of 61 MiB for --patch 1024 (one "
            "column tile of one patch, and one thread's scratch); expected at least 61, or 0 "
            "for no bound") in p.stderr, p.stderr
    assert not out.exists()


def test_import_errors(work):
    junk = work / "junk.tif"
    junk.write_bytes(b"II*\0 this is not really a TIFF")
    ortho = work / "ortho.tif"
    orthographic_off_the_map_tif(ortho)
    cases = [
        (junk, "GDAL cannot open it as a raster"),
        (ortho, "is off the map of unknown (Orthographic)"),
        (work / "no-such.tif", "no such file"),
    ]
    for src, needle in cases:
        out = work / "failed.h5"
        p = run("import", src, "--out", out, check=False)
        assert p.returncode != 0, src
        assert p.stdout == ""
        assert p.stderr.startswith("regolith: error: store::importRaster(): ") and \
            str(src) in p.stderr and needle in p.stderr, p.stderr
        assert not out.exists() and list(work.glob("failed.h5*")) == []
        if "off the map" in needle:
            # info on the same raster: the same reason, non-zero, nothing on stdout.
            p = run("info", src, check=False)
            assert p.returncode != 0 and p.stdout == "" and needle in p.stderr
            assert str(src) in p.stderr
    p = run("info", junk, check=False)
    assert p.returncode != 0 and p.stdout == ""
    assert "not an HDF5 file" in p.stderr and "GDAL cannot open" in p.stderr
    p = run("import", dem_fixture("Shoemaker_1k.tif"), "--out", work / "no" / "such" / "x.h5",
            check=False)
    assert p.returncode != 0
    assert p.stderr == (f"regolith: error: import: --out {work / 'no' / 'such' / 'x.h5'}:"
                        f" folder {work / 'no' / 'such'} does not exist\n")


def test_utm_import_info_and_lonlat_query(work):
    """The NAD27 / UTM 10N fixture imports as a transverse Mercator DEM; `info` shows the
    placement as h5py reads it; `query --coords lonlat` at the NAD27 longitude/latitude that
    gdaltransform gives for pixel centres returns GDAL's sample values there."""
    src = dem_fixture("dem_nodata.dem")
    out = work / "utm.h5"
    run("import", src, "--out", out)
    info = json.loads(run("info", out, "--json").stdout)
    assert info["format_version"] == [1, 4]  # 1.2: transverse Mercator, 1.3: statistics
    g = info["grids"][0]
    assert g["placement"] == {"kind": "transverse_mercator", "lon_centre_deg": -123.0,
                              "lat_origin_deg": 0.0, "scale_factor": 0.9996,
                              "false_easting": 500000.0, "false_northing": 0.0}
    with h5py.File(out, "r") as f:
        a = f["grids/dem_nodata"].attrs
        assert list(a["format_version"]) == [1, 4] and list(f.attrs["format_version"]) == [1, 4]
        assert a["placement"] == b"transverse_mercator"  # a fixed-length string (format 1.4)
        for key in ("lon_centre_deg", "lat_origin_deg", "scale_factor", "false_easting",
                    "false_northing"):
            assert float(a[key]) == g["placement"][key], key
        assert float(a["equatorial_radius"]) == 6378206.4  # Clarke 1866, from the CRS
    text = run("info", out).stdout
    assert ("placement:      transverse_mercator, central meridian -123 deg, origin lat 0 deg, "
            "scale factor 0.9996, false easting 5e+05 m, false northing 0 m") in text

    ds = gdal.Open(src)
    values = ds.GetRasterBand(1).ReadAsArray().astype(np.float64)
    nodata = ds.GetRasterBand(1).GetNoDataValue()
    # Interior pixels (the normal's stencil needs valid neighbours), and nodata pixels.
    pixels = [(r, c) for r in (2, 7, 31, 50, 62) for c in (3, 13, 40, 61)]
    pixels += [tuple(int(v) for v in rc) for rc in np.argwhere(values == nodata)[:3]]
    p = subprocess.run(["gdaltransform", "-t_srs", "EPSG:4267", src],
                       input="".join(f"{c + 0.5} {r + 0.5}\n" for r, c in pixels),
                       capture_output=True, text=True, check=True)
    lonlat = [line.split()[:2] for line in p.stdout.strip().split("\n")]
    assert len(lonlat) == len(pixels)
    points = [f"{lon},{lat}" for lon, lat in lonlat]
    _, rows = parse_csv(run("query", out, "--interp", "nearest", "--", *points).stdout)
    _, body = parse_csv(run("query", out, "--interp", "nearest", "--frame", "body", "--",
                            *points).stdout)
    checked = 0
    for (r, c), row, brow, (lon, lat) in zip(pixels, rows, body, lonlat):
        if values[r, c] == nodata:
            assert row[6] == 0 and math.isnan(row[2]), (r, c)
            continue
        # Next to a hole too, the height is valid (the normal may come from one side).
        assert row[6] == 1 and row[2] == values[r, c], (r, c, row)
        if row[7] == 0:
            continue
        checked += 1
        assert row[6] == 1 and row[2] == values[r, c], (r, c, row)
        # The body-frame normal is a unit vector pointing up, near the ellipsoid normal.
        n = np.array(brow[3:6])
        phi, lam = math.radians(float(lat)), math.radians(float(lon))
        up = np.array([math.cos(phi) * math.cos(lam), math.cos(phi) * math.sin(lam),
                       math.sin(phi)])
        assert abs(np.linalg.norm(n) - 1.0) < 1e-9 and float(n @ up) > 0.5, (r, c, n)
    assert checked >= 15


def projected_tif(path, proj4, centre_xy, values, spacing=100.0):
    """A float32 GeoTIFF in `proj4` whose pixel extent is centred on map point centre_xy."""
    rows, cols = values.shape
    ds = gdal.GetDriverByName("GTiff").Create(str(path), cols, rows, 1, gdal.GDT_Float32)
    srs = osr.SpatialReference()
    srs.ImportFromProj4(proj4)
    ds.SetProjection(srs.ExportToWkt())
    x0 = centre_xy[0] - 0.5 * cols * spacing
    y0 = centre_xy[1] + 0.5 * rows * spacing
    ds.SetGeoTransform([x0, spacing, 0.0, y0, 0.0, -spacing])
    ds.GetRasterBand(1).WriteArray(values.astype(np.float32))
    ds = None
    return x0, y0


def proj_forward(proj4, lon, lat):
    """PROJ's forward projection of one lon/lat (the oracle)."""
    src = osr.SpatialReference()
    src.ImportFromProj4(proj4.split("+proj=")[0] + "+proj=longlat " +
                        " ".join(t for t in proj4.split() if t.startswith(("+R=", "+ellps=",
                                                                            "+datum="))))
    dst = osr.SpatialReference()
    dst.ImportFromProj4(proj4)
    for s in (src, dst):
        s.SetAxisMappingStrategy(osr.OAMS_TRADITIONAL_GIS_ORDER)
    x, y, _ = osr.CoordinateTransformation(src, dst).TransformPoint(lon, lat)
    return x, y


# Issue 16 items 6 and 7: a point the DEM's projection cannot map is a row with valid=0 and
# the reason `unmappable`, never a failed batch; a UTM south DEM (false northing 10,000 km)
# answers lon/lat queries (the height iteration is seeded from the point, not from map (0, 0)).
@pytest.mark.parametrize("name,proj4,lonlat,bad", [
    ("utm10n", "+proj=utm +zone=10 +ellps=WGS84 +units=m +no_defs", (-123.0, 45.0),
     "60,45"),
    ("utm10s", "+proj=utm +zone=10 +south +ellps=WGS84 +units=m +no_defs", (-123.0, -45.0),
     "60,-45"),
    ("south_polar", "+proj=stere +lat_0=-90 +lat_ts=-71 +lon_0=0 +ellps=WGS84 +units=m "
     "+no_defs", (3.0, -87.2), "0,90"),
])
def test_query_unmappable_point_is_a_row_not_a_failure(work, name, proj4, lonlat, bad):
    values = np.arange(400, dtype=np.float64).reshape(20, 20)  # sample (r, c) = 20 r + c
    centre = proj_forward(proj4, *lonlat)
    # The point at the centre of pixel (10, 9).
    x0, y0 = projected_tif(work / f"{name}.tif", proj4, (centre[0] + 50.0, centre[1] + 50.0),
                           values)
    out = work / f"{name}.h5"
    run("import", work / f"{name}.tif", "--out", out)
    good = f"{lonlat[0]!r},{lonlat[1]!r}"
    text = run("query", out, "--interp", "nearest", "--", good, bad, good).stdout
    header, rows = parse_csv(text)
    assert header[-3:] == ["valid", "normal_valid", "reason"]
    assert len(rows) == 3
    # The good point: GDAL's sample at the pixel PROJ puts it in.
    c = int((centre[0] - x0) // 100.0)
    r = int((y0 - centre[1]) // 100.0)
    for row in (rows[0], rows[2]):
        assert row[6:] == [1, 1, "ok"], row
        assert row[2] == values[r, c]
    assert text.split("\n")[2] == f"{bad},nan,nan,nan,nan,0,0,unmappable"
    # Alone, the unmappable point is still a row, and the exit status 0.
    p = run("query", out, "--", bad)
    assert p.stdout.split("\n")[1] == f"{bad},nan,nan,nan,nan,0,0,unmappable"


# Issue 16 item 5: an equirectangular DEM (central meridian 0) whose grid lies on 180 deg and
# reaches past it: its lon/lat queries land where the grid lies (PROJ +over), whatever range
# the longitude is given in.
def test_query_lonlat_on_a_dem_across_the_antimeridian(work):
    proj4 = "+proj=eqc +lon_0=0 +R=3396190 +units=m +no_defs"
    metres_per_deg = 3396190.0 * math.pi / 180.0
    spacing = 2000.0
    values = np.arange(20 * 60, dtype=np.float64).reshape(20, 60)
    x0, y0 = projected_tif(work / "antimeridian.tif", proj4, (180.0 * metres_per_deg, 0.0),
                           values, spacing)
    out = work / "antimeridian.h5"
    run("import", work / "antimeridian.tif", "--out", out)
    cells = [(r, c) for r in (0, 7, 19) for c in (0, 5, 29, 30, 44, 59)]
    points, expected = [], []
    for r, c in cells:
        x = x0 + (c + 0.5) * spacing
        lat = (y0 - (r + 0.5) * spacing) / metres_per_deg
        lon = x / metres_per_deg  # 178 to 182
        for given in (lon, lon - 360.0, lon + 360.0):
            # PROJ with +over keeps the longitude's turn: the oracle for where it lies.
            px, _ = proj_forward(proj4 + " +over", given, lat)
            px += 360.0 * metres_per_deg * round((x - px) / (360.0 * metres_per_deg))
            assert px == pytest.approx(x, abs=1e-6)
            points.append(f"{given!r},{lat!r}")
            expected.append(values[r, c])
    _, rows = parse_csv(run("query", out, "--interp", "nearest", "--", *points).stdout)
    assert [row[6] for row in rows] == [1] * len(points)
    assert [row[2] for row in rows] == expected


# Issue 16 item 8: with every kernel, every valid sample of a real DEM that borders a void has
# a valid height, exactly the sample (21-43 per DEM came back invalid with `nearest` when the
# normal's stencil decided; with bilinear and bicubic, rounding put grid indices 1e-15 off the
# sample, giving the void a weight).
def test_query_samples_next_to_voids_are_valid(work):
    src = dem_fixture("dem_nodata.dem")
    out = work / "voids.h5"
    run("import", src, "--out", out)
    ds = gdal.Open(src)
    values = ds.GetRasterBand(1).ReadAsArray().astype(np.float64)
    void = values == ds.GetRasterBand(1).GetNoDataValue()
    near = np.zeros_like(void)
    near[1:, :] |= void[:-1, :]
    near[:-1, :] |= void[1:, :]
    near[:, 1:] |= void[:, :-1]
    near[:, :-1] |= void[:, 1:]
    border = np.argwhere(near & ~void)
    assert len(border) >= 10
    for interp in ["nearest", "bilinear", "bicubic"]:
        text = run("query", out, "--coords", "grid", "--interp", interp,
                   stdin="".join(f"{r},{c}\n" for r, c in border)).stdout
        _, rows = parse_csv(text)
        assert [row[6] for row in rows] == [1] * len(border), interp
        assert [row[2] for row in rows] == [values[r, c] for r, c in border], interp
        # Their normals come from one side where they have one: unit vectors, or an honest 0.
        for row in rows:
            if row[7] == 1:
                assert abs(math.hypot(*row[3:6]) - 1.0) < 1e-12 and row[8] == "ok"
            else:
                assert math.isnan(row[3]) and row[8] == "nodata"


def read_pty(master, timeout=60):
    seen = b""
    while True:
        ready, _, _ = select.select([master], [], [], timeout)
        if not ready:
            break
        try:
            chunk = os.read(master, 4096)
        except OSError:
            break
        if not chunk:
            break
        seen += chunk
    return seen.decode()


def test_import_progress_only_on_a_terminal(work):
    src = dem_fixture("S11E119.hgt")
    master, slave = pty.openpty()
    try:
        p = subprocess.Popen([BIN, "import", src, "--out", work / "tty-import.h5", "--patch",
                              "64"], stdout=subprocess.PIPE, stderr=slave)
        os.close(slave)
        slave = -1
        text = read_pty(master)
        out, _ = p.communicate(timeout=60)
        assert p.returncode == 0
    finally:
        os.close(master)
        if slave >= 0:
            os.close(slave)
    assert "100%" in text and "[" in text and "\r" in text
    assert out.decode().startswith("Wrote ")  # the summary stays on stdout
    p = run("import", src, "--out", work / "pipe-import.h5", "--patch", 64)
    assert p.stderr == ""


def test_import_interrupted_leaves_no_file(work):
    import signal
    import time
    src = work / "big.tif"
    rows, cols = 3000, 6000
    ds = gdal.GetDriverByName("GTiff").Create(str(src), cols, rows, 1, gdal.GDT_Float32)
    ds.SetGeoTransform([-180.0, 360.0 / cols, 0.0, 90.0, 0.0, -180.0 / rows])
    srs = osr.SpatialReference()
    srs.ImportFromProj4("+proj=longlat +R=3396190 +no_defs")
    ds.SetProjection(srs.ExportToWkt())
    rng = np.random.default_rng(1)
    ds.GetRasterBand(1).WriteArray(rng.standard_normal((rows, cols)).astype(np.float32))
    ds = None
    out = work / "interrupted-import.h5"
    try:
        p = subprocess.Popen([BIN, "import", str(src), "--out", str(out), "--deflate", "9",
                              "--threads", "1"], stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, text=True)
        tmps = f"interrupted-import.h5.tmp-{p.pid}-*"  # core::writeFileAtomically's
        deadline = time.monotonic() + 120
        while not list(work.glob(tmps)) and p.poll() is None and time.monotonic() < deadline:
            time.sleep(0.01)
        assert list(work.glob(tmps)), "the write never started"
        p.send_signal(signal.SIGINT)
        stdout, err = p.communicate(timeout=120)
    finally:
        src.unlink()
    assert p.returncode != 0
    assert err.startswith("regolith: error: ") and "cancelled" in err, err
    assert stdout == ""
    assert not out.exists() and not list(work.glob(tmps))


# ---- query ----------------------------------------------------------------------------------

def bilinear(data, x0, y0, dx, dy, x, y):
    """Height and grid-frame normal of the bilinear patch at (x, y): the numpy oracle."""
    u, v = (x - x0) / dx, (y0 - y) / dy
    c, r = int(math.floor(u)), int(math.floor(v))
    tu, tv = u - c, v - r
    a, b = data[r, c], data[r, c + 1]
    cc, d = data[r + 1, c], data[r + 1, c + 1]
    h = (1 - tv) * ((1 - tu) * a + tu * b) + tv * ((1 - tu) * cc + tu * d)
    dhdx = ((1 - tv) * (b - a) + tv * (d - cc)) / dx
    dhdy = -((1 - tu) * (cc - a) + tu * (d - b)) / dy
    n = np.array([-dhdx, -dhdy, 1.0])
    return h, n / np.linalg.norm(n)


def test_query_bilinear_matches_numpy(victoria):
    data = level0(victoria, "victoria")
    rng = np.random.default_rng(1)
    pts = rng.uniform(-590, 590, size=(200, 2))
    args = [f"{x!r},{y!r}" for x, y in pts]
    header, rows = parse_csv(run("query", victoria, "--coords", "xy", "--", *args).stdout)
    assert header == ["x", "y", "height", "nx", "ny", "nz", "valid", "normal_valid", "reason"]
    assert len(rows) == len(pts)
    for (x, y), row in zip(pts, rows):
        assert row[0] == x and row[1] == y  # coordinates echoed exactly, in input order
        h, n = bilinear(data, -600.0, 600.0, 5.0, 5.0, x, y)
        assert row[6] == 1
        assert row[2] == pytest.approx(h, abs=1e-9)
        assert row[3:6] == pytest.approx(list(n), abs=1e-9)


def test_query_at_sample_centres_returns_the_samples(planet, victoria):
    data = level0(planet, "mars")
    rng = np.random.default_rng(2)
    cells = [(int(r), int(c)) for r, c in zip(rng.integers(0, 60, 50), rng.integers(0, 120, 50))]
    for interp in ["nearest", "bilinear", "bicubic"]:
        _, rows = parse_csv(run("query", planet, "--coords", "grid", "--interp", interp,
                                *[f"{r},{c}" for r, c in cells]).stdout)
        for (r, c), row in zip(cells, rows):
            assert row[2] == data[r, c], (interp, r, c)
        # The same points by longitude and latitude (3° grid: centres at −178.5 + 3c, 88.5 − 3r).
        _, rows = parse_csv(run("query", planet, "--interp", interp, "--",
                                *[f"{-178.5 + 3 * c},{88.5 - 3 * r}" for r, c in cells]).stdout)
        for (r, c), row in zip(cells, rows):
            assert row[2] == data[r, c], (interp, r, c)
    vd = level0(victoria, "victoria")
    _, rows = parse_csv(run("query", victoria, "--coords", "grid", "--interp", "bicubic",
                            "0,0", "120,120", "240,17").stdout)
    assert [row[2] for row in rows] == [vd[0, 0], vd[120, 120], vd[240, 17]]


def test_query_stdin_equals_arguments(victoria, planet):
    pts = ["-5.5,-2.05", "-5.502,-2.049", "-5.497,-2.0531", "-5.4,-2.05"]
    for store in [victoria, planet]:
        for interp in ["nearest", "bilinear", "bicubic"]:
            by_args = run("query", store, "--interp", interp, "--", *pts).stdout
            by_stdin = run("query", store, "--interp", interp,
                           stdin="\n".join(pts) + "\n").stdout
            with_header = run("query", store, "--interp", interp,
                              stdin="lon,lat\n" + "\n".join(pts) + "\n\n# done\n").stdout
            assert by_args == by_stdin == with_header
            assert by_args.startswith("lon,lat,height,nx,ny,nz,valid,normal_valid,reason\n")
            assert len(by_args.strip().split("\n")) == len(pts) + 1


def test_query_negative_points_as_arguments(planet):
    # As docs/cli.md says: '-5.5,...' is a point; '-.5,...' needs -- before the first point.
    a = run("query", planet, "137.4,-4.6", "-5.5,-2.05").stdout
    assert a == run("query", planet, stdin="137.4,-4.6\n-5.5,-2.05\n").stdout
    c = run("query", planet, "--", "-.5,10", "20,30").stdout
    assert c == run("query", planet, stdin="-.5,10\n20,30\n").stdout
    assert "\n-0.5,10," in c


def test_query_nodata_and_outside_rows(h5py_store):
    path, data = h5py_store
    # Sample (r, c) is at x = 100 + 2c, y = 200 - 3r.
    text = run("query", path, "--coords", "xy", "--",
               "142,164",      # (12, 21): nodata (-9999)
               "110,110",      # (30, 5): NaN sample
               "120,170",      # (10, 10): valid
               "1000,1000",    # outside the grid
               "99,201.5").stdout  # on the pixel edge: inside, clamped onto sample (0, 0)
    header, rows = parse_csv(text)
    assert header == ["x", "y", "height", "nx", "ny", "nz", "valid", "normal_valid", "reason"]
    lines = text.strip().split("\n")[1:]
    assert lines[0] == "142,164,nan,nan,nan,nan,0,0,nodata"
    assert lines[1] == "110,110,nan,nan,nan,nan,0,0,nodata"
    assert lines[3] == "1000,1000,nan,nan,nan,nan,0,0,outside"
    assert rows[2][6] == 1 and rows[2][2] == data[10, 10]
    assert rows[4][6] == 1 and rows[4][2] == data[0, 0]
    # Outside in grid coordinates too, and a row for every point still.
    _, rows = parse_csv(run("query", path, "--coords", "grid", "--", "-5,3", "3,60",
                            "3,4").stdout)
    assert [r[6] for r in rows] == [0, 0, 1]


def test_query_lonlat_on_a_dem_agrees_with_proj(victoria):
    """(x, y) -> height; PROJ (cct) turns (x, y, height) into lon/lat; querying that lon/lat
    must find the same terrain point."""
    xs = [0.0, 250.0, -400.0, 520.0]
    ys = [0.0, -130.0, 310.0, 480.0]
    _, rows = parse_csv(run("query", victoria, "--coords", "xy", "--",
                            *[f"{x},{y}" for x, y in zip(xs, ys)]).stdout)
    pipeline = ("+proj=pipeline +step +inv +proj=topocentric +a=3396190 "
                "+b=3376200 +lat_0=-2.05 +lon_0=-5.5 +h_0=-1400 "
                "+step +inv +proj=cart +a=3396190 +b=3376200")
    cct_in = "".join(f"{x} {y} {row[2]}\n" for x, y, row in zip(xs, ys, rows))
    p = subprocess.run(["cct", "-d", "12", *pipeline.split()], input=cct_in,
                       capture_output=True, text=True, check=True)
    lonlat = [line.split()[:2] for line in p.stdout.strip().split("\n")]
    _, back = parse_csv(run("query", victoria, "--",
                            *[f"{lon},{lat}" for lon, lat in lonlat]).stdout)
    for row, b in zip(rows, back):
        assert b[6] == 1
        assert b[2] == pytest.approx(row[2], abs=1e-4)


@pytest.mark.parametrize("args,stdin,needle", [
    (["--", "1,abc"], None, "point 1: lat 'abc' is not a number"),
    (["--", "1,2", "1,2,3"], None, "point 2: '1,2,3' has 3 fields, expected 2 (lon,lat)"),
    (["--", "nan,1"], None, "point 1: lon 'nan' is not a finite number"),
    (["--", "1,inf"], None, "point 1: lat 'inf' is not a finite number"),
    (["--", "1,95"], None, "point 1: lat 95 is outside -90 to 90 degrees"),
    (["--", "5"], None, "point 1: '5' has 1 field, expected 2"),
    ([], "1,2\n3,4\n5;6\n", "stdin line 3"),
    ([], "lon,lat\n1,2\n\n3,x\n", "stdin line 4: lat 'x' is not a number"),
    ([], "lat,lon\n1,2\n", "stdin line 1: header 'lat,lon' does not match"),
    (["--coords", "grid", "--", "1,"], None, "point 1: col '' is not a number"),
])
def test_query_bad_input(victoria, args, stdin, needle):
    p = run("query", victoria, *args, stdin=stdin, check=False)
    assert p.returncode != 0
    assert p.stderr.startswith("regolith: error: query: "), p.stderr
    assert needle in p.stderr, p.stderr
    assert p.stdout == ""  # no partial output


def test_query_store_errors(work, fixture_stores, victoria):
    p = run("query", work / "nope.h5", "1,2", check=False)
    assert p.returncode != 0 and "nope.h5" in p.stderr and "no such file" in p.stderr
    p = run("query", fixture_stores[0], "1,2", check=False)
    assert p.returncode != 0 and "choose one with --grid" in p.stderr
    p = run("query", victoria, "--grid", "olympus", "1,2", check=False)
    assert p.returncode != 0 and "no grid 'olympus'" in p.stderr
    p = run("query", victoria, "--level", "9", "1,2", check=False)
    assert p.returncode != 0 and "level" in p.stderr


def test_query_levels_frames_and_cache(victoria, fixture_stores):
    # Level 1 at its own sample centres returns its own samples.
    with h5py.File(victoria, "r") as f:
        l1 = f["grids/victoria/level1"][...].astype(np.float64)
    _, rows = parse_csv(run("query", victoria, "--level", 1, "--coords", "grid",
                            "5,7", "60,100").stdout)
    assert [r[2] for r in rows] == [l1[5, 7], l1[60, 100]]
    # Body-fixed normals are unit vectors that differ from the grid-frame ones.
    _, grid_n = parse_csv(run("query", victoria, "--coords", "xy", "100,50").stdout)
    _, body_n = parse_csv(run("query", victoria, "--coords", "xy", "--frame", "body",
                              "100,50").stdout)
    assert np.linalg.norm(body_n[0][3:6]) == pytest.approx(1.0, abs=1e-12)
    assert body_n[0][2] == grid_n[0][2]
    assert abs(body_n[0][3] - grid_n[0][3]) > 0.1
    # A tiny cache still answers the same (patches are evicted and reloaded).
    many = [f"{x},{y}" for x in range(-580, 581, 40) for y in range(-580, 581, 40)]
    big = run("query", victoria, "--coords", "xy", "--", *many).stdout
    small = run("query", victoria, "--coords", "xy", "--cache-mb", 1, "--", *many).stdout
    assert big == small
    # A named grid of a multi-grid store.
    p = run("query", fixture_stores[0], "--grid", "mars", "0,0")
    assert p.stdout.startswith("lon,lat,height")


if __name__ == "__main__":
    sys.exit(pytest.main([__file__, "-q"]))


# ---- render ---------------------------------------------------------------------------------

BACKGROUND = np.array([5, 5, 10])  # clod::RenderRequest's default background, in 8 bits


def read_png(path):
    from PIL import Image  # Debian's python3-pil, which python3-matplotlib depends on
    return np.asarray(Image.open(path).convert("RGB")).astype(int)


def terrain_mask(img):
    return np.abs(img - BACKGROUND).sum(axis=2) > 6


def test_render_dem_from_above_matches_a_pinhole_projection(work, h5py_store):
    """Looking straight down, the silhouette's bounding box is where a pinhole camera puts
    the DEM's outermost samples (at their own heights): numpy is the oracle."""
    path, data = h5py_store
    x0, y0, dx, dy = 100.0, 200.0, 2.0, 3.0
    rows, cols = data.shape
    width, height, fov, dist = 320, 240, 40.0, 400.0
    f = (height / 2) / math.tan(math.radians(fov / 2))
    tx = x0 + dx * (cols - 1) / 2
    ty = y0 - dy * (rows - 1) / 2
    th, _ = bilinear(data.astype(np.float64), x0, y0, dx, dy, tx, ty)
    for heading in (0.0, 90.0):
        out = work / f"render-hand-{int(heading)}.png"
        p = run("render", path, "-o", out, "--width", width, "--height", height, "--fov", fov,
                "--elevation", 90, "--distance", dist, "--heading", heading)
        assert f"height {th:.4f}"[:12] in p.stdout, p.stdout
        img = read_png(out)
        assert img.shape == (height, width, 3)
        ys, xs = np.nonzero(terrain_mask(img))
        # Outermost samples (valid ones) and their image positions.
        r, c = np.mgrid[0:rows, 0:cols]
        edge = (r == 0) | (r == rows - 1) | (c == 0) | (c == cols - 1)
        ex, ey, ez = x0 + dx * c[edge], y0 - dy * r[edge], data[edge].astype(np.float64)
        zc = th + dist  # camera height; the camera looks down
        # heading 0: east is right, north up; heading 90: the image's top is east.
        right, upv = ((ex - tx), (ey - ty)) if heading == 0 else (-(ey - ty), (ex - tx))
        px = width / 2 + f * right / (zc - ez)
        py = height / 2 - f * upv / (zc - ez)
        assert xs.min() == pytest.approx(px.min(), abs=1.5)
        assert xs.max() + 1 == pytest.approx(px.max(), abs=1.5)
        assert ys.min() == pytest.approx(py.min(), abs=1.5)
        assert ys.max() + 1 == pytest.approx(py.max(), abs=1.5)


def test_render_planet_disc_has_the_projected_radius(work, planet):
    out = work / "render-mars.png"
    width, height, fov = 300, 300, 45.0
    run("render", planet, "-o", out, "--width", width, "--height", height, "--fov", fov)
    mask = terrain_mask(read_png(out))
    with h5py.File(planet, "r") as f:
        a = float(f["grids/mars"].attrs["equatorial_radius"])
    # Default view: straight down on lon 0, lat 0 from 2 equatorial radii above the surface.
    h0 = level0(planet, "mars")
    centre_h = float(np.nanmean(h0))  # relief is a few km: well under a pixel here
    f_px = (height / 2) / math.tan(math.radians(fov / 2))
    d = a + centre_h + 2 * a
    radius_px = f_px * math.tan(math.asin(a / d))
    row = mask[height // 2]
    cols = np.nonzero(row)[0]
    assert cols.max() + 1 - cols.min() == pytest.approx(2 * radius_px, abs=2.0)
    assert (cols.min() + cols.max() + 1) / 2 == pytest.approx(width / 2, abs=1.0)
    assert not mask[0, 0] and not mask[-1, -1]  # space around the disc


@pytest.mark.parametrize("view", [[], ["--look-at", "20,10", "--distance", 800000, "--elevation", 15]])
def test_render_planet_far_field_covers_what_the_full_clipmap_covers(work, planet, view):
    # With the far field (default) the clipmap keeps its levels within 180° and PGM draws the
    # rest; without it the clipmap draws every level. The planet covers the same pixels but
    # within a pixel of the limb, and the far field changes the picture (it drew something).
    with_ff, without = work / "render-ff.png", work / "render-noff.png"
    run("render", planet, "-o", with_ff, "--width", 240, "--height", 180, *view)
    run("render", planet, "-o", without, "--width", 240, "--height", 180, "--no-far-field", *view)
    a, b = terrain_mask(read_png(with_ff)), terrain_mask(read_png(without))
    assert b.sum() > 1000
    differ = a != b
    # Pixels within one pixel (8-neighbourhood) of the reference's limb may go either way.
    pad = np.pad(b, 1, mode="edge")
    limb = np.zeros_like(b)
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            limb |= pad[1 + dy:1 + dy + b.shape[0], 1 + dx:1 + dx + b.shape[1]] != b
    assert not (differ & ~limb).any(), np.argwhere(differ & ~limb)[:5]
    assert not np.array_equal(read_png(with_ff), read_png(without))


def test_render_oblique_view_of_the_crater(work, victoria):
    out = work / "render-victoria.png"
    p = run("render", victoria, "-o", out, "--width", 400, "--height", 300)
    assert "Wrote" in p.stdout and "patches loaded" in p.stdout
    img = read_png(out)
    mask = terrain_mask(img)
    # Default: the whole DEM in view at 35°: sky above, terrain below, the centre on it.
    assert mask[150, 200] and not mask[0].any() and mask[-40].any()
    assert img[mask].std() > 3  # lit relief, not a flat fill


@pytest.mark.parametrize("args,needle", [
    (["--target", "5000,0"], "outside grid 'victoria'"),
    (["--look-at", "nan,0"], "finite"),
    (["--position", "0,9000,10"], "--position 0,9000 is outside grid 'victoria'"),
    (["--position", "0,0,nan"], "altitude"),
    (["--position", "0,0"], "--position"),
    (["--elevation", "0"], "elevation"),
    (["--width", "4"], "width"),
    (["--grid", "nope"], "nope"),
    (["--clipmap-size", "256"], "odd"),
])
def test_render_errors(work, victoria, args, needle):
    p = run("render", victoria, "-o", work / "bad.png", *args, check=False)
    assert p.returncode != 0
    assert p.stderr.startswith("regolith: error: "), p.stderr
    assert needle in p.stderr, p.stderr
    assert not (work / "bad.png").exists()


def test_render_camera_modes_agree(work, h5py_store):
    """An orbit (look-at, heading, elevation, distance), a camera at a position aimed at the
    same look-at point, and one at that position with the same heading and pitch see the
    same image: the position is given as a grid point and an altitude above the surface
    there, which the test computes with its own bilinear interpolation of the samples."""
    path, data = h5py_store
    x0, y0, dx, dy = 100.0, 200.0, 2.0, 3.0
    heights = data.astype(np.float64)
    tx, ty = 150.0, 140.0
    th, _ = bilinear(heights, x0, y0, dx, dy, tx, ty)
    heading, elevation, dist = 30.0, 60.0, 80.0
    h, e = math.radians(heading), math.radians(elevation)
    fwd = np.array([math.cos(e) * math.sin(h), math.cos(e) * math.cos(h), -math.sin(e)])
    px, py, pz = np.array([tx, ty, th]) - fwd * dist
    ph, _ = bilinear(heights, x0, y0, dx, dy, px, py)
    common = ["--width", 200, "--height", 150]
    images = []
    for i, args in enumerate([
            ["--look-at", f"{tx},{ty}", "--heading", heading, "--elevation", elevation,
             "--distance", dist],
            ["--position", f"{px!r},{py!r},{pz - ph!r}", "--look-at", f"{tx},{ty}"],
            ["--position", f"{px!r},{py!r},{pz - ph!r}", "--heading", heading, "--pitch",
             -elevation]]):
        out = work / f"render-mode-{i}.png"
        run("render", path, "-o", out, *common, *args)
        images.append(read_png(out))
    for img in images[1:]:
        diff = np.abs(img - images[0]).sum(axis=2)
        assert terrain_mask(img).sum() > 1000
        assert diff.mean() < 0.5, diff.mean()
        assert (diff > 30).sum() < 20  # at most a few silhouette pixels


def test_render_needs_a_grid_choice(work, fixture_stores):
    path, _ = fixture_stores
    p = run("render", path, "-o", work / "bad.png", check=False)
    assert p.returncode != 0 and "choose one with --grid" in p.stderr, p.stderr


# ---- demo -----------------------------------------------------------------------------------

def test_demo_generates_then_reuses_its_data_and_writes_every_image(work):
    out = work / "demo"
    args = ["demo", "--quick", "--frames", 3, "--width", 160, "--height", 90, "--out", out]
    first = run(*args, env_render=True)
    assert "generated in" in first.stdout and "==== Summary" in first.stdout
    for name in ["mars.h5", "victoria.h5"]:
        assert (out / "data" / name).exists()
    # The DEM sits on the planet: its placement's origin height is Mars's surface there
    # (h5py reads both; bilinear in the planet's level 0 at the planetocentric latitude).
    a = attrs(out / "data" / "victoria.h5", "victoria")
    m = attrs(out / "data" / "mars.h5", "mars")
    lat_d, lon = float(a["origin_lat_deg"]), float(a["origin_lon_deg"])
    ae, ap = float(m["equatorial_radius"]), float(m["polar_radius"])
    lat_c = math.degrees(math.atan((ap / ae) ** 2 * math.tan(math.radians(lat_d))))
    dx, dy = (float(v) for v in m["spacing"])
    h, _ = bilinear(level0(out / "data" / "mars.h5", "mars"), float(m["x0"]), float(m["y0"]),
                    dx, dy, lon, lat_c)
    assert float(a["origin_height"]) == pytest.approx(h, abs=1e-6)
    images = sorted((out / "flyover").glob("frame_*.png"))
    assert len(images) == 3 and (out / "flyover" / "multiview.png").exists()
    for path in [*images, out / "rover_view.png", out / "rover_chase.png"]:
        assert read_png(path).shape == (90, 160, 3), path
    # The first frame shows Mars whole: space in the corners, the planet in the middle.
    first_frame = terrain_mask(read_png(images[0]))
    assert first_frame[45, 80] and not first_frame[0, 0] and not first_frame[-1, -1]
    second = run(*args, env_render=True)
    # Mars, Victoria, and the caps and strip of the composition.
    assert second.stdout.count("reused") == 3 and "generated in" not in second.stdout


# ---- projections through PROJ, height maps (issue 21) ----------------------------------------

def osr_lonlat(path, pixels):
    """OSR's lon/lat (the CRS's geographic CRS) of GDAL's pixel centres (row, col)."""
    ds = gdal.Open(str(path))
    gt = ds.GetGeoTransform()
    srs = ds.GetSpatialRef()
    srs.SetAxisMappingStrategy(osr.OAMS_TRADITIONAL_GIS_ORDER)
    geo = srs.CloneGeogCS()
    geo.SetAxisMappingStrategy(osr.OAMS_TRADITIONAL_GIS_ORDER)
    ct = osr.CoordinateTransformation(srs, geo)
    return [ct.TransformPoint(gt[0] + (c + 0.5) * gt[1], gt[3] + (r + 0.5) * gt[5])[:2]
            for r, c in pixels]


@pytest.mark.parametrize("name,proj4,body", [
    ("sinusoidal", "+proj=sinu +lon_0=137 +R=3396190 +units=m +no_defs", "Mars"),
    ("lcc", "+proj=lcc +lat_1=-20 +lat_2=-40 +lat_0=-30 +lon_0=30 +R=1737400 +units=m +no_defs",
     "Moon"),
])
def test_projected_crs_import_info_and_lonlat_query(work, name, proj4, body):
    """A sinusoidal (Mars) and an LCC (Moon) DEM import through PROJ; `info` shows the CRS, the
    store records it as WKT2 (format 1.4), and `query` at OSR's lon/lat of pixel centres
    returns GDAL's values there."""
    values = (np.arange(12 * 17).reshape(12, 17) * 1.5 - 300.0).astype(np.float32)
    src = work / f"{name}.tif"
    projected_tif(src, proj4, (24000.0, -150000.0), values, spacing=250.0)
    out = work / f"{name}.h5"
    run("import", src, "--out", out, "--body", body)
    info = json.loads(run("info", out, "--json").stdout)
    assert info["format_version"] == [1, 4]
    g = info["grids"][0]
    assert g["body"]["name"] == body
    assert g["placement"]["kind"] == "projected"
    assert g["placement"]["proj_string"].startswith("+proj=" + proj4.split()[0][6:])
    assert g["placement"]["crs_wkt"].startswith("PROJCRS[")
    with h5py.File(out, "r") as f:
        a = plain_attrs(f[f"grids/{name}"])  # fixed-length text (format 1.4)
        assert a["placement"] == "projected" and a["crs_wkt"] == g["placement"]["crs_wkt"]
    text = run("info", out).stdout
    assert "placement:      projected through PROJ, CRS 'unknown'" in text
    assert "proj string:    " + g["placement"]["proj_string"] in text
    pixels = [(r, c) for r in range(12) for c in range(17)]
    points = [f"{lon!r},{lat!r}" for lon, lat in osr_lonlat(src, pixels)]
    _, rows = parse_csv(run("query", out, "--interp", "nearest", "--", *points).stdout)
    assert [row[2] for row in rows] == [float(values[r, c]) for r, c in pixels]
    # render draws it (straight down on its centre: terrain fills the image's centre).
    png = work / f"{name}.png"
    p = run("render", out, "-o", png, "--width", 160, "--height", 120, "--elevation", 90,
            "--distance", 12000)
    assert "Wrote" in p.stdout
    mask = terrain_mask(read_png(png))
    assert mask[60, 80] and mask.sum() > 0.05 * mask.size and not mask[0, 0]


def test_height_map_png_imports_with_the_flags_and_is_refused_without_them(work):
    """A 16-bit PNG height map: refused without --spacing/--origin/--body (the message names
    them), imported with them: every sample GDAL's value x scale + offset, at (x, y) queries."""
    values = (np.arange(9 * 11).reshape(9, 11) * 311 % 65536).astype(np.uint16)
    mem = gdal.GetDriverByName("MEM").Create("", 11, 9, 1, gdal.GDT_UInt16)
    mem.GetRasterBand(1).WriteArray(values)
    png = work / "height.png"
    gdal.GetDriverByName("PNG").CreateCopy(str(png), mem)
    mem = None
    out = work / "height.h5"
    p = run("import", png, "--out", out, check=False)
    assert p.returncode != 0 and not out.exists()
    assert "--spacing, --origin and --body" in p.stderr and "--height-scale" in p.stderr
    run("import", png, "--out", out, "--spacing", "2,3", "--height-scale", "0.01",
        "--height-offset", "-1400", "--origin", "-2.05,-5.5", "--heading", "30", "--body", "Mars")
    g = json.loads(run("info", out, "--json").stdout)["grids"][0]
    assert g["placement"]["kind"] == "local_tangent_plane"
    assert (g["placement"]["origin_lat_deg"], g["placement"]["origin_lon_deg"]) == (-2.05, -5.5)
    assert g["placement"]["heading_deg"] == 30.0 and g["spacing"] == [2.0, 3.0]
    assert g["geodetic"]["centre"] == {"lat": pytest.approx(-2.05, abs=1e-12),
                                       "lon": pytest.approx(-5.5, abs=1e-12)}
    pixels = [(r, c) for r in range(9) for c in range(11)]
    points = [f"{g['x0'] + 2.0 * c!r},{g['y0'] - 3.0 * r!r}" for r, c in pixels]
    _, rows = parse_csv(run("query", out, "--coords", "xy", "--interp", "nearest", "--",
                            *points).stdout)
    want = [float(np.float32(float(values[r, c]) * 0.01 + -1400.0)) for r, c in pixels]
    assert [row[2] for row in rows] == want


def test_a_corrupt_object_header_gives_one_clear_error_and_no_hdf5_junk(victoria, tmp_path):
    # After a metadata checksum failure HDF5 1.10.8 leaks an internal block; its shutdown at
    # exit used to print "HDF5: infinite loop closing library" and a line of junk after the
    # error (issue 17). The command skips HDF5's shutdown at exit.
    with h5py.File(victoria, "r") as f:
        addr = h5py.h5o.get_info(f["grids/victoria"].id).addr
    data = bytearray(victoria.read_bytes())
    data[addr + 8] ^= 0x10  # one bit of the grid's object header
    bad = tmp_path / "bad-header.h5"
    bad.write_bytes(bytes(data))
    p = run("info", bad, check=False)
    assert p.returncode == 1
    lines = p.stderr.splitlines()
    assert len(lines) == 1, p.stderr
    assert lines[0].startswith(f"regolith: error: store::open(): {bad}: cannot open grid "
                               "'victoria' [HDF5: H5Oopen(): ")
    assert "incorrect metadata checksum" in lines[0]
