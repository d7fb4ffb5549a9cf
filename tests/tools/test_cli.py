"""End-to-end tests of the `regolith` command (docs/cli.md), run by ctest through pytest.

The real binary writes and reads real stores. Oracles from outside the library:
- h5py + numpy read the same stores (docs/store-format.md) for `info --json` and for
  `query` (samples at centres, bilinear heights and normals computed in numpy);
- a store written by h5py itself (not by Regolith) with nodata, for the nodata rows;
- PROJ's `cct` for the geodesy of `--coords lonlat` on a tangent-plane DEM.

Environment: REGOLITH_BIN (the regolith binary), REGOLITH_FIXTURE_WRITER (tests/store's
write_fixture_store, which writes multi-grid and tiled stores).
"""

import json
import math
import os
import pty
import select
import subprocess
import sys

import h5py
import numpy as np
import pytest

BIN = os.environ.get("REGOLITH_BIN", "regolith")
FIXTURE_WRITER = os.environ.get("REGOLITH_FIXTURE_WRITER", "")


def run(*args, stdin=None, check=True):
    p = subprocess.run([BIN, *map(str, args)], input=stdin, capture_output=True, text=True,
                       timeout=300)
    if check and p.returncode != 0:
        raise AssertionError(f"regolith {' '.join(map(str, args))} failed ({p.returncode}):\n"
                             f"{p.stderr}")
    return p


def parse_csv(text):
    lines = text.strip("\n").split("\n")
    header = lines[0].split(",")
    rows = [[float(v) for v in line.split(",")] for line in lines[1:]]
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


def attrs(path, grid):
    with h5py.File(path, "r") as f:
        g = f[f"grids/{grid}"]
        return {k: g.attrs[k] for k in g.attrs}


# ---- --help ---------------------------------------------------------------------------------

@pytest.mark.parametrize("cmd,expect", [
    ([], ["generate", "info", "query", "demo"]),
    (["generate"], ["mars-planet", "victoria"]),
    (["generate", "mars-planet"], ["--seed", "--size", "--resolution", "--out", "--patch",
                                   "--deflate", "--levels", "--ellipsoid", "--craters"]),
    (["generate", "victoria"], ["--seed", "--size", "--resolution", "--out", "--patch",
                                "--deflate"]),
    (["info"], ["--json", "store", "Example"]),
    (["query"], ["--grid", "--interp", "--coords", "--cache-mb", "--frame", "nan", "valid",
                "Example"]),
    (["demo"], ["--size", "--spacing", "--queries", "--out"]),
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
])
def test_usage_errors(args, needle):
    p = run(*args, check=False)
    assert p.returncode != 0
    assert p.stderr.startswith("regolith: error: "), p.stderr
    assert needle in p.stderr
    assert p.stdout == ""
    # The hint names the subcommand that failed.
    words = [a for a in args if a in ("generate", "victoria", "query")]
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
    tmp = work / f"interrupted.h5.tmp-{p.pid}"
    deadline = time.monotonic() + 120
    while not tmp.exists() and p.poll() is None and time.monotonic() < deadline:
        time.sleep(0.01)
    assert tmp.exists(), "the write never started"
    p.send_signal(signal.SIGINT)
    _, err = p.communicate(timeout=120)
    assert p.returncode != 0
    assert err.startswith("regolith: error: ") and "cancelled" in err, err
    assert not out.exists() and not tmp.exists()


# ---- info -----------------------------------------------------------------------------------

def check_info_against_h5py(path, info):
    with h5py.File(path, "r") as f:
        assert info["format_version"] == [int(v) for v in f.attrs["format_version"]]
        names = sorted(f["grids"].keys())
        assert [g["name"] for g in info["grids"]] == names
        for g in info["grids"]:
            h = f["grids"][g["name"]]
            a = h.attrs
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
    assert info["format_version"] == [1, 1]


def test_info_text(victoria, planet):
    text = run("info", victoria).stdout
    for needle in ["grid 'victoria'", "241 rows x 241 cols", "5 x 5 m", "local_tangent_plane",
                   "origin lat -2.05 deg, lon -5.5 deg", "planetodetic", "tiled:          no",
                   "nodata:         none", "patch:          64 x 64", "format version: 1.0"]:
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
    assert header == ["x", "y", "height", "nx", "ny", "nz", "valid"]
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
            assert by_args.startswith("lon,lat,height,nx,ny,nz,valid\n")
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
    assert header == ["x", "y", "height", "nx", "ny", "nz", "valid"]
    lines = text.strip().split("\n")[1:]
    assert lines[0] == "142,164,nan,nan,nan,nan,0"
    assert lines[1] == "110,110,nan,nan,nan,nan,0"
    assert lines[3] == "1000,1000,nan,nan,nan,nan,0"
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
