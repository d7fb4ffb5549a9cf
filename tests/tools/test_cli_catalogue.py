"""End-to-end tests of `regolith query` and `regolith info` on catalogue files (docs/cli.md,
"Catalogue files"), run by ctest through pytest against the real binary.

Oracles from outside the library: the stores are written by h5py alone and the composition
rule is computed in numpy (tests/support/catalogue_fixtures.py): a constant global grid under
a constant regional grid with a feathered border, where "finest wins" gives
H = c h_regional + (1 - c) h_global, and a tangent-plane DEM whose height along a point's
normal is exact geometry. `info` is checked against h5py's reads of the same grids.

Environment: REGOLITH_BIN (the regolith binary).
"""

import csv
import hashlib
import io
import json
import os
import subprocess
import sys

import h5py
import numpy as np
import pytest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "support"))
import catalogue_fixtures as cf  # noqa: E402

BIN = os.environ.get("REGOLITH_BIN", "regolith")
R = cf.MOON[1]
HEADER = ["lon", "lat", "height", "nx", "ny", "nz", "valid", "normal_valid", "reason",
          "contributors"]
EXPLAIN_HEADER = ["lon", "lat", "point", "height", "valid", "reason", "contributors", "dataset",
                  "name", "dataset_height", "coverage", "quality", "share"]


def run(*args, stdin=None, check=True, stdout=subprocess.PIPE):
    p = subprocess.run([BIN, *map(str, args)], input=stdin, stdout=stdout,
                       stderr=subprocess.PIPE, text=True, timeout=300)
    if check and p.returncode != 0:
        raise AssertionError(f"regolith {' '.join(map(str, args))} failed ({p.returncode}):\n"
                             f"{p.stderr}")
    return p


def table(text):
    rows = list(csv.reader(io.StringIO(text)))
    return rows[0], rows[1:]


def refused(*args, needle, stdin=None):
    p = run(*args, stdin=stdin, check=False)
    assert p.returncode != 0, p.stdout
    assert p.stderr.startswith("regolith: error: "), p.stderr
    assert needle in p.stderr, p.stderr
    assert p.stdout == ""  # nothing printed for a command that fails on its input
    return p


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    folder = tmp_path_factory.mktemp("cli-catalogue")
    regional = cf.write_moon_scene(folder)
    glob = {"store": "global.h5", "grid": "global"}
    reg = {"store": "regional.h5", "grid": "regional", "feather_m": cf.FEATHER_M}
    site = {"store": "regional.h5", "grid": "site", "name": "site, the \"DEM\""}
    moon = folder / "moon.json"
    moon.write_text(json.dumps({"policy": "finest", "datasets": [glob, reg, site]}, indent=2))
    only = folder / "regional_only.json"
    only.write_text(json.dumps({"datasets": [reg]}))
    return {"folder": folder, "regional": regional, "moon": moon, "regional_only": only}


def points(n=300, seed=4):
    rng = np.random.default_rng(seed)
    lat = np.concatenate([rng.uniform(-3.0, 13.0, n), np.full(31, 5.0)])
    lon = np.concatenate([rng.uniform(17.0, 33.0, n), np.linspace(19.5, 22.5, 31)])
    return lat, lon


# ---- query ----------------------------------------------------------------------------------


def test_query_heights_and_contributors_follow_the_rule(scene):
    lat, lon = points()
    args = [f"{b!r},{a!r}" for a, b in zip(lat, lon)]
    header, rows = table(run("query", scene["moon"], "--", *args).stdout)
    assert header == HEADER
    assert len(rows) == len(lat)
    want, c, count = cf.finest_wins_oracle(lat, lon, scene["regional"])
    for i, row in enumerate(rows):
        assert float(row[0]) == lon[i] and float(row[1]) == lat[i]  # echoed exactly, in order
        assert row[6:9] == ["1", "1", "ok"]
        assert float(row[2]) == pytest.approx(want[i], abs=1e-9), (lat[i], lon[i])
        assert int(row[9]) == count[i]
    assert {int(r[9]) for r in rows} == {1, 2}
    assert sum(1 for x in c if 0.05 < x < 0.95) > 10  # the feather is sampled


def test_query_normals_across_the_feather(scene):
    lon = np.linspace(20.3, 21.7, 8)
    lat = np.full_like(lon, 5.0)
    args = [f"{b!r},{a!r}" for a, b in zip(lat, lon)]
    _, rows = table(run("query", scene["moon"], *args).stdout)
    n = np.array([[float(v) for v in r[3:6]] for r in rows])
    ge, gn = cf.planet_coverage_gradient(lat, lon, cf.REGIONAL_EXTENT, cf.FEATHER_M, R)
    dh = cf.REGIONAL_H - cf.GLOBAL_H
    want = np.stack([-dh * ge, -dh * gn, np.ones_like(ge)], axis=-1)
    want /= np.linalg.norm(want, axis=-1, keepdims=True)
    np.testing.assert_allclose(n, want, rtol=0, atol=1e-7)
    _, body = table(run("query", scene["moon"], "--frame", "body", *args).stdout)
    for i, r in enumerate(body):
        e, no, u = cf.enu_basis(lat[i], lon[i])
        np.testing.assert_allclose([float(v) for v in r[3:6]],
                                   n[i, 0] * e + n[i, 1] * no + n[i, 2] * u, atol=1e-12)
        assert r[2] == rows[i][2]  # the frame changes the normal only


def test_query_a_tangent_plane_dem_and_a_hole(scene):
    lat0, lon0 = cf.SITE_ORIGIN
    pts = [(lat0, lon0), (lat0 + 0.05, lon0 - 0.07), (5.0, 28.0)]  # (5, 28): the NaN block
    _, rows = table(run("query", scene["moon"], *[f"{b},{a}" for a, b in pts]).stdout)
    for (a, b), row in zip(pts[:2], rows):
        assert float(row[2]) == pytest.approx(
            cf.tangent_plane_height(a, b, lat0, lon0, cf.SITE_H, R), abs=1e-6)
        assert row[9] == "1"  # the DEM hides the global grid
    assert float(rows[2][2]) == cf.GLOBAL_H and rows[2][9] == "1"


def test_query_stdin_equals_arguments(scene):
    pts = ["21,5", "25.5,4", "-100,-40", "40,-30"]
    by_args = run("query", scene["moon"], *pts).stdout
    by_stdin = run("query", scene["moon"], stdin="\n".join(pts) + "\n").stdout
    with_header = run("query", scene["moon"], stdin="lon,lat\n# c\n" + "\n".join(pts)).stdout
    assert by_args == by_stdin == with_header
    assert by_args.startswith(",".join(HEADER) + "\n")
    assert len(by_args.strip().split("\n")) == len(pts) + 1


def test_query_outside_every_dataset_is_a_row_not_a_failure(scene):
    text = run("query", scene["regional_only"], "25,5", "100,50", "-0.5,89.9").stdout
    lines = text.strip().split("\n")
    assert lines[1].startswith("25,5,250,") and lines[1].endswith(",1,1,ok,1")
    assert lines[2] == "100,50,nan,nan,nan,nan,0,0,outside,0"
    assert lines[3] == "-0.5,89.9,nan,nan,nan,nan,0,0,outside,0"


def test_explain_gives_each_points_shares(scene):
    lat, lon = points(n=40, seed=9)
    args = [f"{b!r},{a!r}" for a, b in zip(lat, lon)] + ["40,-30"]
    header, rows = table(run("query", scene["moon"], "--explain", *args).stdout)
    assert header == EXPLAIN_HEADER
    _, c, count = cf.finest_wins_oracle(lat, lon, scene["regional"])
    q = cf.planet_quality(lat)
    by_point = {}
    for r in rows:
        by_point.setdefault(int(r[2]), []).append(r)
    assert sorted(by_point) == list(range(1, len(args) + 1))
    for i in range(len(lat)):
        shares = by_point[i + 1]
        assert len(shares) == (2 if c[i] > 0 else 1)  # every covering dataset has a row
        assert int(shares[0][6]) == count[i]  # those with a non-zero share
        assert sum(float(s[12]) for s in shares) == pytest.approx(1.0, abs=1e-12)
        composed = float(shares[0][3])
        assert composed == pytest.approx(sum(float(s[12]) * float(s[9]) for s in shares),
                                         abs=1e-9)
        named = {s[8]: s for s in shares}
        assert named["global"][7] == "0" and float(named["global"][9]) == cf.GLOBAL_H
        assert float(named["global"][11]) == pytest.approx(q[i], abs=1e-12)
        if c[i] > 0:
            reg = named["regional"]
            assert reg[7] == "1" and float(reg[9]) == cf.REGIONAL_H
            assert float(reg[10]) == pytest.approx(c[i], abs=1e-12)
            assert float(reg[12]) == pytest.approx(c[i], abs=1e-12)
            assert float(named["global"][12]) == pytest.approx(1.0 - c[i], abs=1e-12)
    # The DEM, whose name holds a comma and quotes (quoted as CSV), hides the global grid.
    site = by_point[len(args)]
    assert [(s[7], s[8], s[12]) for s in site] == [("2", 'site, the "DEM"', "1"),
                                                    ("0", "global", "0")]


def test_explain_outside_every_dataset_has_one_empty_row(scene):
    text = run("query", scene["regional_only"], "--explain", "100,50").stdout
    assert text.strip().split("\n")[1] == "100,50,1,nan,0,outside,0,,,nan,nan,nan,nan"


# ---- errors ---------------------------------------------------------------------------------


@pytest.mark.parametrize("name,text,needle", [
    ("typo.json", {"datasets": [{"store": "global.h5", "grid": "global", "feather": 5}]},
     "compose::readCatalogueFile(): {path}: datasets[0] key 'feather' is 5, expected one of "
     "store, grid, name, role, priority, feather_m, height_offset_m, mask_grid, "
     "feather_nodata_samples"),
    ("top.json", {"datasets": [{"store": "global.h5", "grid": "global"}], "rules": 1},
     "compose::readCatalogueFile(): {path}: key 'rules' is 1, expected one of policy, "
     "resolution_power, tier_ratio, datasets"),
    ("policy.json", {"policy": "best", "datasets": [{"store": "global.h5", "grid": "global"}]},
     "policy is 'best', expected weighted or finest"),
    ("empty.json", {"datasets": []}, "expected a non-empty array of datasets"),
    ("notjson.json", "{datasets: ", "{path}: JSON is [json.exception.parse_error"),
    ("nogrid.json", {"datasets": [{"store": "global.h5", "grid": "nope"}]}, "'nope'"),
    ("nostore.json", {"datasets": [{"store": "missing.h5", "grid": "g"}]}, "missing.h5"),
    ("feather.json", {"datasets": [{"store": "regional.h5", "grid": "regional",
                                    "feather_m": -1}]},
     "datasets[0].feather_m is -1, expected within 0 .. 1e+08"),
])
def test_bad_catalogue_files_are_refused_with_the_librarys_message(scene, name, text, needle):
    path = scene["folder"] / name
    path.write_text(text if isinstance(text, str) else json.dumps(text))
    for command in (["query", path, "1,2"], ["query", path, "--explain", "1,2"], ["info", path],
                    ["info", path, "--json"]):
        p = refused(*command, needle=needle.format(path=path))
        assert p.returncode == 1
        assert "Traceback" not in p.stderr and len(p.stderr.strip().split("\n")) == 1


def test_catalogue_on_two_bodies_and_files_that_are_neither(scene, tmp_path):
    mars = tmp_path / "mars.h5"
    run("generate", "mars-planet", "--out", mars, "--size", 30, "--patch", 16)
    two = tmp_path / "two.json"
    two.write_text(json.dumps({"datasets": [
        {"store": str(scene["folder"] / "global.h5"), "grid": "global"},
        {"store": str(mars), "grid": "mars"}]}))
    refused("query", two, "1,2", needle="expected datasets[0]'s body Moon")
    text = tmp_path / "points.txt"
    text.write_text("1,2\n")
    refused("query", text, "1,2",
            needle=f"query: {text} is neither a store (no HDF5 signature) nor a catalogue file")
    refused("query", tmp_path / "absent.json", "1,2", needle="absent.json")


@pytest.mark.parametrize("args,needle", [
    (["--grid", "global"], "query: --grid applies to a store's grid, but {moon} is a catalogue"),
    (["--level", "1"], "query: --level applies to a store's grid"),
    (["--interp", "bicubic"], "query: --interp applies to a store's grid"),
    (["--coords", "xy"], "query: --coords applies to a store's grid"),
    (["--", "1,95"], "query: point 1: lat 95 is outside -90 to 90 degrees"),
    (["--", "nan,1"], "query: point 1: lon 'nan' is not a finite number"),
])
def test_query_options_and_points_a_catalogue_refuses(scene, args, needle):
    refused("query", scene["moon"], *args, *([] if "--" in args else ["1,2"]),
            needle=needle.format(moon=scene["moon"]))


def test_explain_on_a_store_is_refused_and_lonlat_is_accepted(scene):
    store = scene["folder"] / "global.h5"
    refused("query", store, "--explain", "1,2",
            needle=f"query: --explain shows how a catalogue file's datasets share a composed "
                   f"height, but {store} is a store")
    assert run("query", scene["moon"], "--coords", "lonlat", "25,5").stdout == run(
        "query", scene["moon"], "25,5").stdout


def test_stdout_appended_to_a_store_of_the_catalogue_is_refused(scene):
    store = scene["folder"] / "regional.h5"
    before = hashlib.sha256(store.read_bytes()).hexdigest()
    for command in (["query", scene["moon"], "25,5"], ["info", scene["moon"]]):
        with open(store, "a") as appended:
            p = run(*command, stdout=appended, check=False)
        assert p.returncode != 0
        assert f"standard output is the input {store}" in p.stderr
        assert hashlib.sha256(store.read_bytes()).hexdigest() == before


# ---- info -----------------------------------------------------------------------------------


def test_info_json_lists_the_datasets_as_h5py_reads_them(scene):
    j = json.loads(run("info", scene["moon"], "--json").stdout)
    assert j["path"] == str(scene["moon"])
    assert j["body"] == {"name": "Moon", "equatorial_radius": R, "polar_radius": R}
    assert j["policy"] == "finest" and j["resolution_power"] == 2.0 and j["tier_ratio"] == 4.0
    ds = j["datasets"]
    assert [d["name"] for d in ds] == ["global", "regional", 'site, the "DEM"']
    assert [d["kind"] for d in ds] == ["planet", "planet", "dem"]
    assert [d["placement"] for d in ds] == [None, None, "local_tangent_plane"]
    assert [d["feather_m"] for d in ds] == [0, cf.FEATHER_M, 0]
    assert [d["role"] for d in ds] == ["height"] * 3
    for d, (store, grid) in zip(ds, [("global.h5", "global"), ("regional.h5", "regional"),
                                     ("regional.h5", "site")]):
        with h5py.File(scene["folder"] / store, "r") as f:
            a = f[f"grids/{grid}"].attrs
            dx, dy = a["spacing"]
            rows, cols = int(a["rows"]), int(a["cols"])
            assert (d["rows"], d["cols"], d["spacing"]) == (rows, cols, [dx, dy])
            assert d["extent"] == {"west": a["x0"] - dx / 2, "east": a["x0"] + (cols - 0.5) * dx,
                                   "north": a["y0"] + dy / 2,
                                   "south": a["y0"] - (rows - 0.5) * dy}
            data = f[f"grids/{grid}/level0"][...]
            assert d["height_range"] == [np.nanmin(data), np.nanmax(data)]
            assert d["levels"] == int(a["levels"])
    assert ds[2]["centre"]["lat"] == pytest.approx(cf.SITE_ORIGIN[0], abs=1e-9)
    assert ds[2]["centre"]["lon"] == pytest.approx(cf.SITE_ORIGIN[1], abs=1e-9)
    assert ds[1]["centre"] == {"lat": 5.0, "lon": 25.0}
    lo, hi = np.array(ds[2]["bounds"]["min"]), np.array(ds[2]["bounds"]["max"])
    centre = (R + cf.SITE_H) * cf.enu_basis(*cf.SITE_ORIGIN)[2]
    assert np.all(centre >= lo) and np.all(centre <= hi)


def test_info_text_names_every_dataset(scene):
    out = run("info", scene["moon"]).stdout
    assert out.startswith(f"catalogue:      {scene['moon']}\n")
    assert "rules:          policy finest, resolution power 2, tier ratio 4\n" in out
    assert "datasets:       3\n" in out
    assert "dataset 1 'regional' (id 2)" in out
    assert "feather 60000 m" in out
    assert "placement:      local_tangent_plane" in out
    assert "extent:         lon 20 to 30, lat 0 to 10 deg (pixel edges)" in out


def test_help_mentions_catalogues(scene):
    q = run("query", "--help").stdout
    for needle in ["catalogue", "--explain", "planetodetic", "contributors", "moon.json"]:
        assert needle in q, needle
    assert "catalogue" in run("info", "--help").stdout
