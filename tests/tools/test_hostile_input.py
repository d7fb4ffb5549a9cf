"""Hostile input to the `regolith` command (docs/reliability.md, "Catalogue of hostile input").

Each case is what a careless user or an attacker would try: an output that is one of the
inputs (by name, symlink or hard link), NaN and infinite camera numbers, a camera inside the
body, georeferencing no body can have, a height spike, a symlink loop, a UTF-8 byte-order
mark on stdin, an unknown subcommand. Every case must end with a clear error naming what is
wrong, exit non-zero, and leave every input byte for byte as it was (hashlib is the oracle).
Rasters are written by GDAL (osgeo.gdal); imported samples are compared with h5py reads.

Environment: as tests/tools/test_cli.py (REGOLITH_BIN, REGOLITH_FIXTURES_DIR).
"""

import hashlib
import os
import shutil
import subprocess
import sys

import h5py
import numpy as np
import pytest
from osgeo import gdal, osr

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from test_cli import BIN, NO_LEAK_CHECK, dem_fixture, parse_csv, run, summary_field  # noqa: E402

gdal.UseExceptions()

SAME_FILE = "output is the same file as the input"


def digest(path):
    return hashlib.sha256(open(path, "rb").read()).hexdigest()


def refused(*args, needle, stdout=None):
    """Runs regolith with args; asserts a non-zero exit and an error containing needle."""
    p = subprocess.run([BIN, *map(str, args)], stdout=stdout or subprocess.PIPE,
                       stderr=subprocess.PIPE, text=True, timeout=300,
                       env={**os.environ, **NO_LEAK_CHECK})
    assert p.returncode != 0, f"regolith {args} exited 0"
    assert p.stderr.startswith("regolith: error: "), p.stderr
    assert needle in p.stderr, p.stderr
    return p.stderr


def tif(path, geotransform, values, proj4="+proj=longlat +R=3396190 +no_defs",
        dtype=gdal.GDT_Float64):
    rows, cols = values.shape
    ds = gdal.GetDriverByName("GTiff").Create(str(path), cols, rows, 1, dtype)
    srs = osr.SpatialReference()
    srs.ImportFromProj4(proj4)
    ds.SetProjection(srs.ExportToWkt())
    ds.SetGeoTransform(geotransform)
    ds.GetRasterBand(1).WriteArray(values)
    ds = None
    return path


def geographic_tif(path, geotransform, values):
    return tif(path, geotransform, values)


def eqc_tif(path, geotransform, values):
    return tif(path, geotransform, values, "+proj=eqc +R=3396190 +units=m +no_defs",
               gdal.GDT_Float32)


@pytest.fixture(scope="module")
def work(tmp_path_factory):
    return tmp_path_factory.mktemp("hostile")


@pytest.fixture(scope="module")
def small_tif(work):
    """A 12 x 16 geographic patch near Gale crater, heights a plane in metres."""
    r, c = np.mgrid[0:12, 0:16]
    return geographic_tif(work / "small.tif", [137.0, 0.01, 0.0, -4.0, 0.0, -0.01],
                          (10.0 * c - 5.0 * r - 4000.0).astype(np.float64))


@pytest.fixture(scope="module")
def store(work):
    path = work / "v.h5"
    run("generate", "victoria", "--out", path, "--size", 65, "--resolution", 8, "--patch", 32)
    return path


# ---- 1. no output may be one of the inputs --------------------------------------------------

@pytest.mark.parametrize("how", ["same name", "symlink", "hard link", "dot path"])
def test_import_refuses_to_write_over_its_source(work, small_tif, how):
    src = work / f"src-{how.replace(' ', '_')}.tif"
    shutil.copy(small_tif, src)
    out = {"same name": src, "dot path": src.parent / "." / src.name}.get(how)
    if how == "symlink":
        out = work / "link-to-src.h5"
        out.unlink(missing_ok=True)
        out.symlink_to(src)
    elif how == "hard link":
        out = work / "hard-link-to-src.h5"
        out.unlink(missing_ok=True)
        os.link(src, out)
    before = digest(src)
    err = refused("import", src, "--out", out, needle=SAME_FILE)
    assert f"store::importRaster(): {out}: {SAME_FILE} {src}" in err
    assert digest(src) == before


def test_import_refuses_to_write_over_the_data_file_of_a_label(work):
    # A PDS3 label with a detached data file: the data file is an input too.
    for name in ["megt90n000cb.lbl", "megt90n000cb.img"]:
        shutil.copy(dem_fixture(name), work / name)
    before = digest(work / "megt90n000cb.img")
    refused("import", work / "megt90n000cb.lbl", "--out", work / "megt90n000cb.img",
            needle=f"{SAME_FILE} {work / 'megt90n000cb.img'}")
    assert digest(work / "megt90n000cb.img") == before


def test_import_tiles_refuses_to_write_over_a_tile(work, small_tif):
    r, c = np.mgrid[0:12, 0:16]
    east = geographic_tif(work / "east.tif", [137.16, 0.01, 0.0, -4.0, 0.0, -0.01],
                          (1.0 * c + r).astype(np.float64))
    before = digest(east)
    refused("import", small_tif, east, "--out", east,
            needle=f"store::importTiles(): {east}: {SAME_FILE} {east}")
    assert digest(east) == before


@pytest.mark.parametrize("target", ["store", "symlink", "legend"])
def test_render_refuses_to_write_over_its_store(work, store, target):
    out = {"store": store}.get(target)
    if target == "symlink":
        out = work / "render-link.png"
        out.unlink(missing_ok=True)
        out.symlink_to(store)
    elif target == "legend":  # the side output <out>.legend.json
        out = work / "side.png"
        legend = work / "side.png.legend.json"
        legend.unlink(missing_ok=True)
        os.link(store, legend)
    before = digest(store)
    refused("render", store, "-o", out, needle=SAME_FILE)
    assert digest(store) == before


@pytest.mark.parametrize("command", [["info"], ["query", "--coords", "grid"]])
def test_commands_refuse_stdout_appended_to_their_store(work, store, command):
    before = digest(store)
    args = [command[0], store, *command[1:]] + (["1,1"] if command[0] == "query" else [])
    with open(store, "ab") as appended:
        refused(*args, needle=f"{command[0]}: standard output is the input {store}",
                stdout=appended)
    assert digest(store) == before


def test_demo_refuses_to_render_over_its_data(work):
    out, data = work / "demo-out", work / "demo-data"
    out.mkdir(exist_ok=True)
    run("demo", "--quick", "--frames", 2, "--width", 64, "--height", 64, "--data", data,
        "--out", work / "demo-first", check=False)  # only to make the data: may fail later
    victoria = data / "victoria.h5"
    assert victoria.exists()
    (out / "rover_view.png").unlink(missing_ok=True)
    (out / "rover_view.png").symlink_to(victoria)
    before = digest(victoria)
    refused("demo", "--quick", "--frames", 2, "--width", 64, "--height", 64, "--data", data,
            "--out", out, needle=f"demo: {out / 'rover_view.png'}: {SAME_FILE} {victoria}")
    assert digest(victoria) == before


# ---- 2. camera numbers ----------------------------------------------------------------------

@pytest.mark.parametrize("args,needle", [
    (["--heading", "nan"], "--heading: Value nan is not a finite number in [-360, 360]"),
    (["--heading", "inf"], "--heading: Value inf is not a finite number in [-360, 360]"),
    (["--distance", "nan"], "--distance: Value nan is not a finite number"),
    (["--elevation", "nan"], "--elevation: Value nan is not a finite number"),
    (["--fov", "nan"], "--fov: Value nan is not a finite number in [1, 170]"),
    (["--position", "0,0,10", "--pitch", "nan"], "--pitch: Value nan is not a finite number"),
    (["--look-at", "0,inf"], "--look-at: Value inf is not a finite number"),
    (["--position", "0,0,-2e6"],
     "render: --position altitude is -2e+06 m, expected finite and >= 0 (below the surface "
     "the camera is inside the body and sees no terrain)"),
    (["--position", "0,0,-1"], "--position altitude is -1 m"),
])
def test_render_refuses_bad_camera_numbers(work, store, args, needle):
    out = work / "camera.png"
    refused("render", store, "-o", out, *args, needle=needle)
    assert not out.exists()


def test_generate_refuses_nan_resolution(work):
    refused("generate", "victoria", "--out", work / "nan.h5", "--resolution", "nan",
            needle="--resolution: Value nan is not a finite number > 0")
    assert not (work / "nan.h5").exists()


# ---- 2. impossible georeferencing, spikes ---------------------------------------------------

def test_import_refuses_a_pixel_of_1e300_degrees(work):
    src = geographic_tif(work / "huge_pixel.tif", [0.0, 1e300, 0.0, 90.0, 0.0, -1.0],
                         np.zeros((4, 4)))
    refused("import", src, "--out", work / "huge_pixel.h5",
            needle=f"store::importRaster(): {src}: pixel width is 1e+300 deg, expected at most "
                   "360 deg (one pixel cannot be larger than the body)")
    assert not (work / "huge_pixel.h5").exists()


def test_import_refuses_a_dem_wider_than_the_body(work):
    # Equirectangular metres 720 deg wide: two circumferences of Mars.
    radius = 3396190.0
    cols = 40
    dx = 2 * 2 * np.pi * radius / cols
    src = eqc_tif(work / "wide.tif", [-cols * dx / 2, dx, 0.0, 1000.0, 0.0, -dx],
                  np.zeros((2, cols), dtype=np.float32))
    needle = " deg of longitude, expected at most 360 deg (one pixel more for a rounded pixel size)"
    err = refused("import", src, "--out", work / "wide.h5",
                  needle=f"store::importRaster(): {src}: grid width (40 columns of")
    assert needle in err
    degrees = float(err.split(" is ")[-1].split(" deg")[0])
    assert abs(degrees - 720.0) < 0.01  # GDAL's radius of the CRS, to a few metres
    refused("info", src, needle=needle)
    assert not (work / "wide.h5").exists()


def test_import_refuses_a_west_edge_beyond_360_degrees(work):
    src = geographic_tif(work / "far_west.tif", [1000.0, 1.0, 0.0, 10.0, 0.0, -1.0],
                         np.zeros((4, 4)))
    refused("import", src, "--out", work / "far_west.h5",
            needle=f"{src}: west edge longitude is 1000 deg, expected within -360 to 360 deg")


def spike_tif(work):
    values = np.full((8, 8), -2500.0)
    values[3, 5] = 1e30
    values[6, 1] = -4e5
    return geographic_tif(work / "spike.tif", [137.0, 0.01, 0.0, -4.0, 0.0, -0.01], values)


def test_import_counts_implausible_heights(work, small_tif):
    src = spike_tif(work)
    out = work / "spike.h5"
    p = run("import", src, "--out", out)
    assert summary_field(p.stdout, "warning") == (
        "2 samples beyond +-339619 m (a tenth of the body's radius): a spike, or a wrong scale "
        "or unit? --strict refuses them")
    with h5py.File(out, "r") as f:  # written as they are, not clipped
        level0 = f["grids/spike/level0"][...]
    assert level0[3, 5] == np.float32(1e30) and level0[6, 1] == -4e5
    clean = run("import", small_tif, "--out", work / "clean.h5")
    assert "warning" not in clean.stdout


def test_import_strict_refuses_implausible_heights(work):
    src = spike_tif(work)
    out = work / "spike-strict.h5"
    err = refused("import", src, "--out", out, "--strict",
                  needle=f"store::importRaster(): {src}: sample at row ")
    assert ": sample at row 3, col 5 is 1e+30 m, expected within +-339619 m (a tenth of the " \
        "body's radius; --strict / strict=True refuses heights beyond it)" in err
    assert not out.exists()


def test_import_names_the_source_for_samples_beyond_float(work):
    values = np.full((4, 4), 10.0)
    values[2, 1] = 1e300  # a float64 that float32 cannot hold
    src = geographic_tif(work / "overflow.tif", [137.0, 0.01, 0.0, -4.0, 0.0, -0.01], values)
    out = work / "overflow.h5"
    refused("import", src, "--out", out,
            needle=f"store::importRaster(): {src}: sample at row 2, col 1 is inf m, expected "
                   "finite (a source value beyond float's range after scale and offset)")
    assert not out.exists()


# ---- 3. messages ----------------------------------------------------------------------------

def symlink_loop(work, stem):
    """<stem>-a.h5 -> <stem>-b.h5 -> <stem>-a.h5; returns the first."""
    a, b = work / f"{stem}-a.h5", work / f"{stem}-b.h5"
    for link, target in [(a, b), (b, a)]:
        if not link.is_symlink():
            link.symlink_to(target)
    return a


@pytest.mark.parametrize("command", [["info"], ["query", "--coords", "grid", "1,1"],
                                     ["render", "-o", "OUT"], ["import", "--out", "OUT"]])
def test_symlink_loops_are_named(work, command):
    a = symlink_loop(work, "loop")
    args = [command[0], a] + [str(work / "loop-out.h5") if x == "OUT" else x
                              for x in command[1:]]
    refused(*args, needle=f"{a}: symlink loop (too many levels of symbolic links)")


def test_generate_output_that_is_a_symlink_loop_is_named(work):
    a = symlink_loop(work, "gen-loop")
    refused("generate", "victoria", "--out", a, "--size", 17,
            needle=f"generate victoria: {a}: symlink loop (too many levels of symbolic links)")
    assert a.is_symlink()  # not replaced by a store


@pytest.mark.parametrize("command", [["walkthrough", "--size", 17, "--queries", 1000],
                                     ["demo", "--quick", "--frames", 2]])
def test_output_folders_that_are_symlink_loops_or_files_are_refused_first(work, small_tif,
                                                                           command):
    a = symlink_loop(work, "dir-loop")
    err = refused(*command, "--out", a,
                  needle=f"{command[0]}: {a}: symlink loop (too many levels of symbolic links)")
    assert "filesystem error" not in err
    refused(*command, "--out", small_tif,
            needle=f"{command[0]}: --out {small_tif} is a file, expected a folder")


def test_render_output_that_is_a_symlink_loop_is_named(work, store):
    a = symlink_loop(work, "png-loop")
    refused("render", store, "-o", a,
            needle=f"render: {a}: symlink loop (too many levels of symbolic links)")


def test_query_strips_a_utf8_byte_order_mark(store):
    plain = run("query", store, "--coords", "grid", stdin="row,col\n1,1\n2.5,3\n").stdout
    bom = run("query", store, "--coords", "grid", stdin="\ufeffrow,col\n1,1\n2.5,3\n").stdout
    assert bom == plain
    header, rows = parse_csv(bom)
    assert len(rows) == 2 and header[0] == "row"
    # Without a header line, the mark would have been glued to the first number.
    assert run("query", store, "--coords", "grid", stdin="\ufeff1,1\n").stdout == run(
        "query", store, "--coords", "grid", stdin="1,1\n").stdout


@pytest.mark.parametrize("extra", [[], ["--help"], ["--out", "x"]])
def test_an_unknown_subcommand_is_named(extra):
    p = subprocess.run([BIN, "nosuchcmd", *extra], capture_output=True, text=True, timeout=60)
    assert p.returncode != 0
    assert p.stdout == ""  # not the main help
    assert p.stderr.startswith(
        "regolith: error: unknown subcommand 'nosuchcmd', expected one of: "), p.stderr
    for name in ["demo", "generate", "import", "info", "query", "render", "walkthrough"]:
        assert name in p.stderr
