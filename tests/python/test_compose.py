"""pytest suite of catalogue files and composed surfaces in the regolith Python module
(regolith.read_catalogue, Catalogue, ComposedSurface), run by ctest.

Outside oracles: the stores are written by h5py alone (tests/support/catalogue_fixtures.py),
and the composition rule of docs/composition.md is computed in numpy for constant-height
grids on a sphere, where it has a closed form: a global grid under a finer regional grid with
a feathered border ("finest wins": H = c h_regional + (1 - c) h_global with c the smoothstep of
the distance to the border; "weighted": w = c q (spacing ratio)^p), and a tangent-plane DEM,
whose height along a point's normal is exact geometry.
"""

import json
import os
import sys
import threading

import h5py
import numpy as np
import pytest

import regolith

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "support"))
import catalogue_fixtures as cf  # noqa: E402

R = cf.MOON[1]


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    folder = tmp_path_factory.mktemp("compose")
    regional = cf.write_moon_scene(folder)

    def catalogue(name, policy, datasets, **rules):
        path = folder / name
        path.write_text(json.dumps({"policy": policy, **rules, "datasets": datasets}))
        return path

    glob = {"store": "global.h5", "grid": "global"}
    reg = {"store": "regional.h5", "grid": "regional", "feather_m": cf.FEATHER_M}
    site = {"store": str(folder / "regional.h5"), "grid": "site", "name": "site, the DEM"}
    return {
        "folder": folder,
        "regional": regional,
        "finest": catalogue("finest.json", "finest", [glob, reg, site]),
        # A tier ratio above the grids' spacing ratio (8): one tier, blended by weight.
        "weighted": catalogue("weighted.json", "weighted", [glob, reg], tier_ratio=10),
        "regional_only": catalogue("regional_only.json", "finest", [reg]),
    }


def points_around_the_regional_grid(n=400, seed=3):
    rng = np.random.default_rng(seed)
    lat = rng.uniform(-3.0, 13.0, n)
    lon = rng.uniform(17.0, 33.0, n)
    # And a line across the west border's feather, where the blend is.
    line_lon = np.linspace(19.5, 22.5, 61)
    return np.concatenate([lat, np.full(61, 5.0)]), np.concatenate([lon, line_lon])


# ---- the catalogue ------------------------------------------------------------------------


def test_catalogue_lists_its_datasets_as_h5py_reads_their_grids(scene):
    c = regolith.read_catalogue(scene["finest"])
    assert isinstance(c, regolith.Catalogue) and len(c) == 3
    assert c.policy == "finest" and c.resolution_power == 2.0
    assert c.body == {"name": "Moon", "equatorial_radius": R, "polar_radius": R}
    ds = c.datasets
    assert [d["index"] for d in ds] == [0, 1, 2]
    assert [d["name"] for d in ds] == ["global", "regional", "site, the DEM"]
    assert [d["kind"] for d in ds] == ["planet", "planet", "dem"]
    assert [d["placement"] for d in ds] == [None, None, "local_tangent_plane"]
    assert [d["feather_m"] for d in ds] == [0.0, cf.FEATHER_M, 0.0]
    assert all(d["role"] == "height" and d["priority"] == 0 and not d["mask"] for d in ds)
    for d, (store, grid) in zip(ds, [("global.h5", "global"), ("regional.h5", "regional"),
                                     ("regional.h5", "site")]):
        with h5py.File(scene["folder"] / store, "r") as f:
            a = f[f"grids/{grid}"].attrs
            dx, dy = a["spacing"]
            assert (d["rows"], d["cols"]) == (int(a["rows"]), int(a["cols"]))
            assert d["spacing"] == (dx, dy)
            assert d["extent"] == {"west": a["x0"] - dx / 2,
                                   "east": a["x0"] + (int(a["cols"]) - 0.5) * dx,
                                   "north": a["y0"] + dy / 2,
                                   "south": a["y0"] - (int(a["rows"]) - 0.5) * dy}
            level0 = f[f"grids/{grid}/level0"][...]
            assert d["height_range"] == (np.nanmin(level0), np.nanmax(level0))
    # Ground spacing: a planet grid's meridian arc of one latitude step, a DEM's spacing.
    assert ds[0]["ground_spacing_m"] == pytest.approx(R * cf.GLOBAL_STEP * cf.DEG, rel=1e-12)
    assert ds[1]["ground_spacing_m"] == pytest.approx(R * cf.REGIONAL_STEP * cf.DEG, rel=1e-12)
    assert ds[2]["ground_spacing_m"] == cf.SITE_SPACING
    # The regional grid's body-fixed box holds its corners (at its height).
    lo, hi = np.array(ds[1]["bounds"]["min"]), np.array(ds[1]["bounds"]["max"])
    for lat in (0.0, 10.0):
        for lon in (20.0, 30.0):
            p = (R + cf.REGIONAL_H) * cf.enu_basis(lat, lon)[2]
            assert np.all(p >= lo) and np.all(p <= hi)
    assert "3 datasets on Moon" in repr(c)
    assert regolith.Catalogue(scene["finest"]).datasets == ds


# ---- heights against the rule in numpy ----------------------------------------------------


def test_finest_wins_heights_match_the_rule(scene):
    s = regolith.read_catalogue(scene["finest"]).surface()
    assert s.policy == "finest"
    lat, lon = points_around_the_regional_grid()
    want, c, count = cf.finest_wins_oracle(lat, lon, scene["regional"])
    h, st, n = s.heights(lat, lon, status=True, contributors=True)
    assert np.all(st == regolith.STATUS_OK)
    np.testing.assert_allclose(h, want, rtol=0, atol=1e-9)
    np.testing.assert_array_equal(n, count)
    # Inside (past the feather) the regional height, outside the global one, exactly.
    assert np.any(c == 1.0) and np.all(h[c == 1.0] == cf.REGIONAL_H)
    assert np.any(c == 0.0) and np.all(h[c == 0.0] == cf.GLOBAL_H)
    # The blend is there: points strictly inside the feather.
    assert np.sum((c > 0.05) & (c < 0.95)) > 20


def test_weighted_heights_match_the_rule_for_two_powers_and_tier_ratios(scene):
    cat = regolith.read_catalogue(scene["weighted"])
    assert cat.policy == "weighted" and cat.tier_ratio == 10.0
    lat, lon = points_around_the_regional_grid(seed=5)
    for power, s in [(2.0, cat.surface()), (1.0, cat.surface(resolution_power=1.0)),
                     (2.0, cat.surface(tier_ratio=float("inf")))]:
        assert s.policy == "weighted" and s.resolution_power == power
        want = cf.weighted_oracle(lat, lon, scene["regional"], power)
        np.testing.assert_allclose(s.heights(lat, lon), want, rtol=0, atol=1e-9)
    # A tier ratio below the spacing ratio (8; the default is 4) puts the regional grid in a
    # tier of its own over the global one: its coverage is the alpha, as under "finest".
    want, _, _ = cf.finest_wins_oracle(lat, lon, scene["regional"])
    for s in [cat.surface(tier_ratio=4.0), cat.surface(tier_ratio=7.9), cat.surface(policy="finest")]:
        np.testing.assert_allclose(s.heights(lat, lon), want, rtol=0, atol=1e-9)
    assert cat.surface(tier_ratio=4.0).tier_ratio == 4.0


def test_a_nodata_hole_leaves_the_global_height(scene):
    s = regolith.read_catalogue(scene["finest"]).surface()
    # The centre of the NaN block (rows 18-21, cols 30-33): lat 5, lon 28.
    h, st, n = s.heights(np.array([5.0]), np.array([28.0]), status=True, contributors=True)
    assert h[0] == cf.GLOBAL_H and st[0] == regolith.STATUS_OK and n[0] == 1
    assert [w["name"] for w in s.weights(5.0, 28.0)] == ["global"]


def test_a_tangent_plane_dem_gives_its_plane_along_the_normal(scene):
    s = regolith.read_catalogue(scene["finest"]).surface()
    lat0, lon0 = cf.SITE_ORIGIN
    # Within 4 km of the DEM's centre (its extent is +-5050 m): 0.13 degrees of latitude.
    rng = np.random.default_rng(11)
    lat = lat0 + rng.uniform(-0.12, 0.12, 50)
    lon = lon0 + rng.uniform(-0.12, 0.12, 50) / np.cos(lat0 * cf.DEG)
    h, n = s.heights(lat, lon, contributors=True)
    want = [cf.tangent_plane_height(a, b, lat0, lon0, cf.SITE_H, R) for a, b in zip(lat, lon)]
    np.testing.assert_allclose(h, want, rtol=0, atol=1e-6)
    assert np.all(n == 1)  # the DEM hides the global grid: one dataset has a share
    shares = s.weights(lat[0], lon[0])
    assert [(w["dataset"], w["name"], w["share"]) for w in shares] == [
        (2, "site, the DEM", 1.0), (0, "global", 0.0)]


# ---- normals --------------------------------------------------------------------------------


def test_normals_across_the_feather_are_the_gradient_of_the_rule(scene):
    s = regolith.read_catalogue(scene["finest"]).surface()
    lon = np.linspace(20.3, 21.7, 15)  # inside the west border's feather, far from the others
    lat = np.full_like(lon, 5.0)
    h, n, st, nst, k = s.surfaces(lat, lon, status=True, normal_status=True, contributors=True)
    assert np.all(st == regolith.STATUS_OK) and np.all(nst == regolith.STATUS_OK)
    assert np.all(k == 2)
    ge, gn = cf.planet_coverage_gradient(lat, lon, cf.REGIONAL_EXTENT, cf.FEATHER_M, R)
    dh = cf.REGIONAL_H - cf.GLOBAL_H
    want = np.stack([-dh * ge, -dh * gn, np.ones_like(ge)], axis=-1)
    want /= np.linalg.norm(want, axis=-1, keepdims=True)
    np.testing.assert_allclose(n, want, rtol=0, atol=1e-7)
    assert np.all(np.abs(n[:, 0]) > 1e-4)  # the feather does tilt the surface
    # Body-fixed: the same vector in the ENU basis of each point.
    _, nb = s.surfaces(lat, lon, frame="body")
    for i in range(len(lat)):
        e, no, u = cf.enu_basis(lat[i], lon[i])
        np.testing.assert_allclose(nb[i], n[i, 0] * e + n[i, 1] * no + n[i, 2] * u, atol=1e-12)
    # Far from any border the constant heights are flat.
    _, n_flat = s.surfaces(np.array([5.0, -40.0]), np.array([25.0, -100.0]))
    np.testing.assert_allclose(n_flat, [[0, 0, 1], [0, 0, 1]], atol=1e-12)


# ---- shares -------------------------------------------------------------------------------


def test_weights_are_the_rule_written_out(scene):
    lat, lon = 5.0, 20.9
    c = float(cf.planet_coverage(lat, lon, cf.REGIONAL_EXTENT, cf.FEATHER_M, R))
    q = float(cf.planet_quality(lat))
    assert 0.1 < c < 0.9
    finest = regolith.read_catalogue(scene["finest"]).surface()
    w = finest.weights(lat, lon)
    assert [(x["dataset"], x["name"]) for x in w] == [(1, "regional"), (0, "global")]
    assert [x["height"] for x in w] == [cf.REGIONAL_H, cf.GLOBAL_H]
    assert w[0]["coverage"] == pytest.approx(c, abs=1e-12) and w[1]["coverage"] == 1.0
    assert w[0]["quality"] == pytest.approx(q, abs=1e-12)
    assert w[1]["quality"] == pytest.approx(q, abs=1e-12)
    assert w[0]["share"] == pytest.approx(c, abs=1e-12)
    assert w[1]["share"] == pytest.approx(1.0 - c, abs=1e-12)
    assert sum(x["share"] * x["height"] for x in w) == pytest.approx(
        finest.height(lat, lon), abs=1e-9)
    weighted = regolith.read_catalogue(scene["weighted"]).surface()
    w = {x["name"]: x["share"] for x in weighted.weights(lat, lon)}
    wr, wg = c * q, q / 64.0
    assert w["regional"] == pytest.approx(wr / (wr + wg), abs=1e-12)
    assert w["global"] == pytest.approx(wg / (wr + wg), abs=1e-12)
    # Nothing covers a point outside a regional-only catalogue.
    only = regolith.read_catalogue(scene["regional_only"]).surface()
    assert only.weights(50.0, 100.0) == []
    assert np.isnan(only.height(50.0, 100.0))


# ---- batches, statuses, shapes, threads ---------------------------------------------------


def test_batches_equal_single_queries_and_keep_their_shape(scene):
    s = regolith.read_catalogue(scene["finest"]).surface()
    lat, lon = points_around_the_regional_grid(n=60, seed=8)
    lat, lon = lat[:60].reshape(6, 10), lon[:60].reshape(6, 10)
    h = s.heights(lat, lon)
    assert h.shape == (6, 10) and h.dtype == np.float64
    assert [s.height(a, b) for a, b in zip(lat.ravel(), lon.ravel())] == list(h.ravel())
    h2, n, k = s.surfaces(lat, lon, contributors=True)
    assert n.shape == (6, 10, 3) and k.shape == (6, 10) and k.dtype == np.uint32
    np.testing.assert_array_equal(h2, h)
    np.testing.assert_array_equal(s.heights(lat, lon, contributors=True)[1], k)
    out = np.empty((6, 10))
    assert s.heights(lat, lon, out=out) is out or np.array_equal(out, h)
    np.testing.assert_array_equal(out, h)
    on = (np.empty((6, 10)), np.empty((6, 10, 3)))
    s.surfaces(lat, lon, out=on)
    np.testing.assert_array_equal(on[0], h)
    np.testing.assert_array_equal(on[1], n)
    # Lists and integer arrays are numbers too.
    assert s.heights([5, 5], [25, 19]).tolist() == [cf.REGIONAL_H, cf.GLOBAL_H]


def test_bad_points_get_a_status_not_an_exception(scene):
    s = regolith.read_catalogue(scene["regional_only"]).surface()
    lat = np.array([5.0, np.nan, 5.0, 91.0, -np.inf, 50.0])
    lon = np.array([25.0, 25.0, np.inf, 25.0, 25.0, 100.0])
    h, st, k = s.heights(lat, lon, status=True, contributors=True)
    assert h[0] == cf.REGIONAL_H and st[0] == regolith.STATUS_OK and k[0] == 1
    assert np.all(np.isnan(h[1:])) and np.all(st[1:] == regolith.STATUS_OUTSIDE)
    assert np.all(k[1:] == 0)
    h2, n, st2, nst, k2 = s.surfaces(lat, lon, status=True, normal_status=True,
                                     contributors=True)
    np.testing.assert_array_equal(st2, st)
    np.testing.assert_array_equal(k2, k)
    assert np.all(np.isnan(n[1:])) and np.all(nst[1:] == regolith.STATUS_OUTSIDE)
    # One point at a time, a bad coordinate is a caller's error.
    with pytest.raises(regolith.InvalidArgument, match=r"latitude is nan, expected a finite"):
        s.height(np.nan, 0.0)
    with pytest.raises(ValueError, match=r"latitude is 91 deg, expected within -90 .. 90"):
        s.weights(91.0, 0.0)


@pytest.mark.parametrize("bad,needle", [
    (np.array([1 + 2j]), "dtype complex128 (its imaginary part would be dropped)"),
    (np.array([None], dtype=object), "dtype object (None and other objects are not numbers)"),
    (np.array([True]), "dtype bool"),
    (np.array(["5"]), "dtype <U1"),
])
def test_arrays_that_are_not_real_numbers_are_refused(scene, bad, needle):
    s = regolith.read_catalogue(scene["finest"]).surface()
    for call in (lambda: s.heights(bad, np.zeros(1)), lambda: s.surfaces(np.zeros(1), bad)):
        with pytest.raises(regolith.InvalidArgument) as e:
            call()
        assert needle in str(e.value)
        assert "expected real numbers" in str(e.value)


def test_shapes_outputs_and_options_are_checked(scene):
    cat = regolith.read_catalogue(scene["finest"])
    s = cat.surface()
    with pytest.raises(ValueError, match=r"ComposedSurface.heights\(\): lat has shape \(3,\) "
                                         r"and lon has shape \(2,\), expected the same shape"):
        s.heights(np.zeros(3), np.zeros(2))
    with pytest.raises(ValueError, match=r"out has shape \(2,\), expected the shape"):
        s.heights(np.zeros(3), np.zeros(3), out=np.empty(2))
    with pytest.raises(ValueError, match=r"out must be a \(heights, normals\) tuple"):
        s.surfaces(np.zeros(3), np.zeros(3), out=np.empty(3))
    with pytest.raises(ValueError, match=r"normal frame 'enu' is unknown"):
        s.surfaces(np.zeros(3), np.zeros(3), frame="enu")
    with pytest.raises(ValueError, match=r"policy 'best' is unknown, expected 'weighted' or "
                                         r"'finest'"):
        cat.surface(policy="best")
    with pytest.raises(ValueError, match=r"rules.resolutionPower is -1, expected finite, >= 0"):
        cat.surface(resolution_power=-1.0)
    with pytest.raises(ValueError, match=r"rules.tierRatio is 0.5, expected >= 1"):
        cat.surface(tier_ratio=0.5)
    with pytest.raises(ValueError, match=r"cache_bytes is 0"):
        regolith.read_catalogue(scene["finest"], cache_bytes=0)


def test_threads_query_one_surface_at_once(scene):
    cat = regolith.read_catalogue(scene["finest"], cache_bytes=1 << 20)
    s = cat.surface()
    lat, lon = points_around_the_regional_grid(n=2000, seed=13)
    want = s.heights(lat, lon)
    results = [None] * 4

    def work(i):
        results[i] = s.surfaces(lat, lon)[0]

    threads = [threading.Thread(target=work, args=(i,)) for i in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for r in results:
        np.testing.assert_array_equal(r, want)
    stats = cat.cache_stats()
    assert stats["capacity_bytes"] == 1 << 20 and stats["loads"] > 0


# ---- bad catalogue files --------------------------------------------------------------------


@pytest.mark.parametrize("name,text,error,needles", [
    ("typo.json", {"datasets": [{"store": "global.h5", "grid": "global", "feather": 5}]},
     regolith.InvalidArgument, ["typo.json", "datasets[0] key 'feather'",
                                "expected one of store, grid"]),
    ("top.json", {"dataset": []}, regolith.InvalidArgument, ["top.json", "key 'dataset'"]),
    ("policy.json", {"policy": "best", "datasets": [{"store": "global.h5", "grid": "global"}]},
     regolith.InvalidArgument, ["policy.json", "policy is 'best', expected weighted or finest"]),
    ("empty.json", {"datasets": []}, regolith.InvalidArgument, ["non-empty array of datasets"]),
    ("notjson.json", "{datasets: ", regolith.InvalidArgument, ["notjson.json", "valid JSON"]),
    ("nogrid.json", {"datasets": [{"store": "global.h5", "grid": "nope"}]},
     regolith.StoreError, ["nope"]),
    ("nostore.json", {"datasets": [{"store": "missing.h5", "grid": "g"}]},
     regolith.StoreError, ["missing.h5"]),
    ("feather.json", {"datasets": [{"store": "regional.h5", "grid": "regional",
                                    "feather_m": -1}]},
     regolith.InvalidArgument, ["datasets[0].feather_m is -1"]),
])
def test_bad_catalogue_files_raise_the_librarys_error(scene, name, text, error, needles):
    path = scene["folder"] / name
    path.write_text(text if isinstance(text, str) else json.dumps(text))
    with pytest.raises(error) as e:
        regolith.read_catalogue(path)
    for needle in needles:
        assert needle in str(e.value), str(e.value)
    assert str(e.value).startswith(("compose::readCatalogueFile(): ", "store::open(): ",
                                    "Store::grid()", "store::"))


def test_datasets_on_two_bodies_and_a_missing_file(scene, tmp_path):
    mars = tmp_path / "mars.h5"
    regolith.generate_mars(mars, rows=30, patch_size=16)
    path = tmp_path / "two_bodies.json"
    path.write_text(json.dumps({"datasets": [
        {"store": str(scene["folder"] / "global.h5"), "grid": "global"},
        {"store": str(mars), "grid": "mars"}]}))
    with pytest.raises(regolith.InvalidArgument, match=r"expected datasets\[0\]'s body Moon"):
        regolith.read_catalogue(path)
    with pytest.raises(regolith.IoError, match=r"absent.json"):
        regolith.read_catalogue(tmp_path / "absent.json")
