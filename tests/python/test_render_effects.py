"""Dem.render(effects=..., height_range=...) and Planet.render(effects=...) (docs/python.md,
"Effects"; docs/overlays.md), run by ctest.

Outside oracles: the store is written by h5py (a plane h = A + B·x + C·y on a local tangent
plane), so the ground point of every pixel of a straight-down view is a ray–plane
intersection in numpy; the height ramp is clod::kHeightRamp's stops written down here;
lat/lon lines are counted against PROJ's cct. The module is found through PYTHONPATH.
"""

import math
import subprocess

import h5py
import numpy as np
import pytest

import regolith

RAMP = np.array([[0.19, 0.21, 0.58], [0.13, 0.57, 0.55], [0.37, 0.79, 0.38],
                 [0.99, 0.91, 0.15], [0.85, 0.16, 0.12]])
A, B, C = 10.0, 0.06, -0.04
N, D = 401, 2.0  # 800 m square, centred on the origin
LAT0, LON0 = 10.0, 20.0
MARS_A, MARS_B = 3396190.0, 3376200.0
W, H, FOV = 240, 180, 40.0


@pytest.fixture(scope="module")
def plane(tmp_path_factory):
    path = tmp_path_factory.mktemp("effects") / "plane.h5"
    half = D * (N - 1) / 2
    r, c = np.mgrid[0:N, 0:N]
    data = (A + B * (-half + D * c) + C * (half - D * r)).astype("<f4")
    with h5py.File(path, "w") as f:
        f.attrs["regolith_store"] = "made by h5py"
        f.attrs["format_version"] = np.array([1, 0], dtype="<i4")
        g = f.create_group("grids/plane")
        attrs = {
            "format_version": np.array([1, 0], dtype="<i4"), "kind": "dem",
            "rows": np.uint64(N), "cols": np.uint64(N), "x0": -half, "y0": half,
            "spacing": np.array([D, D]), "units": "m", "sample_type": "float32",
            "scale": 1.0, "offset": 0.0, "nodata": np.float32(-9999.0), "body": "Mars",
            "equatorial_radius": MARS_A, "polar_radius": MARS_B,
            "latitude_type": "planetodetic", "levels": np.uint64(1),
            "patch_shape": np.array([64, 64], dtype="<u8"),
            "placement": "local_tangent_plane", "origin_lat_deg": LAT0,
            "origin_lon_deg": LON0, "origin_height": 0.0, "heading_deg": 0.0,
        }
        for k, v in attrs.items():
            g.attrs[k] = v
        g.create_dataset("level0", data=data, chunks=(64, 64))
    return path, data


def down(dist, **kw):
    """A view down on the origin from `dist` metres above the plane, north up: the camera at
    (0, 0, A + dist) in the grid frame, pitched 89.99° down (0.01° from straight down moves
    the ground under a pixel by 0.02 % of the distance, a twentieth of a pixel)."""
    return dict(position=(0.0, 0.0, A + dist), heading_deg=0.0, pitch_deg=-89.99, width=W,
                height=H, fov_deg=FOV, near=1.0, **kw)


def ground(dist):
    """Ground (x, y, h) of each pixel centre of down(dist), taken as straight down."""
    f = (H / 2) / math.tan(math.radians(FOV / 2))
    py, px = np.mgrid[0:H, 0:W] + 0.5
    dx, dy = (px - W / 2) / f, -(py - H / 2) / f
    t = dist / (1.0 + B * dx + C * dy)  # ray (0, 0, A + dist) + t (dx, dy, -1) on the plane
    x, y = t * dx, t * dy
    return x, y, A + B * x + C * y


def ramp_colour(h, lo, hi):
    t = np.clip((h - lo) / (hi - lo), 0.0, 1.0) * 4.0
    k = np.minimum(np.floor(t).astype(int), 3)
    f = (t - k)[..., None]
    return (RAMP[k] * (1 - f) + RAMP[k + 1] * f) * 255.0


def test_height_colours_follow_the_ramp_over_height_range(plane):
    path, data = plane
    dem = regolith.open(path)
    img = dem.render(**down(250.0), effects=["height-colours"], height_range=(0.0, 40.0),
                     legend=False)[..., :3].astype(int)
    _, _, h = ground(250.0)
    err = np.abs(img - ramp_colour(h, 0.0, 40.0)).max(axis=2)
    assert np.percentile(err, 99) <= 4 and err.max() <= 10, (np.percentile(err, 99), err.max())
    # The same with the range in the dict, and by default the grid's own range (h5py's).
    same = dem.render(**down(250.0), effects={"height-colours": {"range": (0, 40)}},
                      legend=False)[..., :3].astype(int)
    np.testing.assert_array_equal(same, img)
    default = dem.render(**down(250.0), effects="height-colours", legend=False)
    err = np.abs(default[..., :3] - ramp_colour(h, float(data.min()), float(data.max())))
    assert np.percentile(err.max(axis=2), 99) <= 4
    # With the legend: the panel in the top-right corner, the rest unchanged.
    with_legend = dem.render(**down(250.0), effects=["height-colours"], height_range=(0, 40))
    changed = np.abs(with_legend[..., :3].astype(int) - img).sum(axis=2) > 0
    ys, xs = np.nonzero(changed)
    assert changed.sum() > 1000 and ys.min() >= 8 and ys.max() < H - 20 and xs.min() > W / 3


def test_the_three_spellings_of_effects_agree_and_noise_is_deterministic(plane):
    path, _ = plane
    dem = regolith.open(path)
    bare = dem.render(**down(150.0)).astype(int)
    a = dem.render(**down(150.0), effects=["noise", "latlon"])
    b = dem.render(**down(150.0), effects="latlon, noise")
    c = dem.render(**down(150.0), effects={"noise": None, "latlon": True, "tracks": False})
    np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(a, c)
    noisy = dem.render(**down(150.0), effects={"noise": {"amplitude": 0.5, "wavelength": 8.0,
                                                          "octaves": 3}}).astype(int)
    again = dem.render(**down(150.0), effects={"noise": {"amplitude": 0.5, "wavelength": 8.0,
                                                          "octaves": 3}}).astype(int)
    np.testing.assert_array_equal(noisy, again)
    assert (np.abs(noisy - bare)[..., :3].sum(axis=2) > 3).mean() > 0.5


def test_latlon_lines_on_a_placed_dem_as_many_as_proj_counts(plane):
    path, _ = plane
    dem = regolith.open(path)
    spacing, dist = 0.003, 1200.0
    bare = dem.render(**down(dist)).astype(int)
    lined = dem.render(**down(dist), effects={"latlon": {"spacing": spacing}},
                       legend=False).astype(int)
    line = np.abs(lined - bare)[..., :3].sum(axis=2) > 60
    x, y, h = ground(dist)
    row = H // 2
    inside = np.abs(x[row]) < 240  # within the clipmap's one level (254 cells of 2 m a side)
    pipeline = (f"+proj=pipeline +step +inv +proj=topocentric +a={MARS_A} +b={MARS_B} "
                f"+lat_0={LAT0} +lon_0={LON0} +h_0=0 +step +inv +proj=cart +a={MARS_A} "
                f"+b={MARS_B}")
    text = "".join(f"{a!r} {b!r} {c!r}\n" for a, b, c in
                   zip(x[row, inside], y[row, inside], h[row, inside]))
    out = subprocess.run(["cct", "-d", "12", *pipeline.split()], input=text,
                         capture_output=True, text=True, check=True).stdout
    lon = np.array([float(line_.split()[0]) for line_ in out.strip().split("\n")])
    expected = np.count_nonzero(np.diff(np.floor(lon / spacing)))
    runs = np.count_nonzero(np.diff(line[row, inside].astype(int)) == 1)
    assert expected >= 2 and runs == expected, (runs, expected)
    assert line.sum() < 0.2 * W * H  # lines, not a fill


def test_tracks_by_keyword_and_by_effects_draw_the_same_ruts(plane):
    path, _ = plane
    dem = regolith.open(path)
    layer = regolith.TrackLayer()
    for y in np.arange(-6.0, 6.0, 0.05):
        layer.step(np.array([[-1.1, y], [1.1, y]]))
    view = down(20.0)
    bare = dem.render(**view).astype(int)
    legacy = dem.render(**view, tracks=layer)
    named = dem.render(**view, effects={"tracks": layer})
    also = dem.render(**view, effects=["tracks"], tracks=layer)
    np.testing.assert_array_equal(legacy, named)
    np.testing.assert_array_equal(legacy, also)
    diff = legacy.astype(int)[..., :3].sum(axis=2) - bare[..., :3].sum(axis=2)
    changed = np.abs(diff) > 6
    x, y, _ = ground(20.0)
    assert changed.sum() > 100 and diff[changed].sum() < 0
    off = np.minimum(np.abs(np.abs(x) - 1.1), 99.0)
    assert off[changed].max() < 0.2 + 0.05 + 0.1  # half a rut, a texel, a pixel


@pytest.mark.parametrize("kwargs,message", [
    (dict(effects=["fog"]), "regolith.render(): effects 'fog' is not an effect, expected one "
     "of tracks, height-colours, latlon, noise"),
    (dict(effects="noise,,latlon"), "regolith.render(): effects 'noise,,latlon' has an empty "
     "name, expected names separated by commas, each one of tracks, height-colours, latlon, "
     "noise"),
    (dict(effects=3), "regolith.render(): effects is a int, expected None, a list of effect "
     "names, a comma-separated str or a dict name -> parameters"),
    (dict(effects=["noise", 4]), "regolith.render(): effects holds a int, expected effect "
     "names (str)"),
    (dict(effects={"noise": {"amp": 1}}), "regolith.render(): effects['noise'] has no "
     "parameter 'amp', expected amplitude, wavelength, octaves"),
    (dict(effects={"noise": {"octaves": 9}}), "regolith.render(): effects['noise']['octaves'] "
     "is 9, expected 1 to 8"),
    (dict(effects={"noise": {"octaves": 2.5}}), "regolith.render(): "
     "effects['noise']['octaves'] is a float, expected an int (1 to 8)"),
    (dict(effects={"noise": {"amplitude": "big"}}), "regolith.render(): "
     "effects['noise']['amplitude'] is a str, expected a number"),
    (dict(effects={"latlon": {"spacing": float("nan")}}), "regolith.render(): "
     "effects['latlon']['spacing'] is nan deg, expected 0 (adapts to the view) or finite and "
     "within [1e-06, 90] deg"),
    (dict(height_range=(0, 5)), "regolith.render(): height_range sets a parameter of "
     "height-colours, which effects does not name"),
    (dict(effects=["height-colours"], height_range=(5, 5)), "regolith.render(): height_range "
     "is 5,5 m, expected low < high (as 32-bit floats)"),
    (dict(effects=["height-colours"], height_range=(0, math.inf)), "regolith.render(): "
     "height_range is 0,inf m, expected low,high finite and within [-1e+06, 1e+06] m"),
    (dict(effects={"height-colours": {"range": (1, 2)}}, height_range=(0, 5)),
     "regolith.render(): give height_range or effects['height-colours']['range'], not both"),
    (dict(effects={"height-colours": {"range": (3, 2)}}), "regolith.render(): "
     "effects['height-colours']['range'] is 3,2 m, expected low < high (as 32-bit floats)"),
    (dict(effects=["tracks"]), "regolith.render(): effect 'tracks' needs a TrackLayer (the "
     "ruts a traverse pressed): tracks=layer or effects={'tracks': layer}"),
])
def test_effect_errors_word_for_word(plane, kwargs, message):
    path, _ = plane
    dem = regolith.open(path)
    with pytest.raises(regolith.InvalidArgument) as e:
        dem.render(**down(100.0), **kwargs)
    assert str(e.value) == message


def test_tracks_on_a_planet_and_a_layer_without_the_effect_are_refused(tmp_path, plane):
    mars = tmp_path / "mars.h5"
    regolith.generate_mars(mars, rows=60)
    planet = regolith.open(mars)
    with pytest.raises(regolith.InvalidArgument) as e:
        planet.render(position=(8e6, 0.0, 0.0), heading_deg=0.0, pitch_deg=-89.99, width=32,
                      height=32, clipmap_size=61, effects={"tracks": regolith.TrackLayer()})
    assert str(e.value) == ("regolith.render(): effect 'tracks' needs a DEM (ruts are in "
                            "metres), and grid 'mars' is a planet")
    dem = regolith.open(plane[0])
    with pytest.raises(regolith.InvalidArgument) as e:
        dem.render(**down(100.0), effects=["noise"], tracks=regolith.TrackLayer())
    assert str(e.value) == ("regolith.render(): tracks sets the layer of tracks, which effects "
                            "does not name")
    # A planet with lat/lon lines and height colours: lines only with the effect.
    view = dict(position=(8e6, 0.0, 0.0), heading_deg=0.0, pitch_deg=-89.99, width=96,
                height=96, clipmap_size=61)
    bare = planet.render(**view).astype(int)
    lined = planet.render(**view, effects={"latlon": {"spacing": 30}}, legend=False)
    changed = np.abs(lined.astype(int) - bare)[..., :3].sum(axis=2) > 60
    assert changed[:, 48].sum() > 20 and changed.sum() < 0.5 * (bare[..., :3].sum(axis=2) > 30).sum()
