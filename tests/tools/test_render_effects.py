"""`regolith render --effects ...` (docs/cli.md, "Effects"; docs/overlays.md), run by ctest
through pytest on the real binary.

Oracles from outside the library:
- the stores are written by h5py (docs/store-format.md): a planar DEM h = A + B·x + C·y on a
  local tangent plane, so the ground point of every pixel of a straight-down view is a
  ray–plane intersection in double, in numpy;
- the height ramp is clod::kHeightRamp's five stops, written down here, interpolated in
  numpy (clod::heightColour's rule);
- PROJ's `cct` turns the ground points (tangent-plane metres) into longitude and latitude
  for the lat/lon lines;
- the rover's wheel track (RoverGeometry: 2.20 m between wheel centres, axles at +1.10 and
  −1.00 m) and the rut width (0.40 m) bound where tracks may darken the ground.

Environment: REGOLITH_BIN (the regolith binary); REGOLITH_REFERENCE_BIN (optional: a build
from before the effects options, whose bare images must equal this build's byte for byte).
"""

import json
import math
import os
import subprocess

import h5py
import numpy as np
import pytest

BIN = os.environ.get("REGOLITH_BIN", "regolith")
REFERENCE_BIN = os.environ.get("REGOLITH_REFERENCE_BIN", "")
NO_LEAK_CHECK = {"ASAN_OPTIONS": os.environ.get("ASAN_OPTIONS", "") + ":detect_leaks=0"}

# clod::kHeightRamp (clod/Effects.hpp): blue -> green -> yellow -> red.
RAMP = np.array([[0.19, 0.21, 0.58], [0.13, 0.57, 0.55], [0.37, 0.79, 0.38],
                 [0.99, 0.91, 0.15], [0.85, 0.16, 0.12]])
BACKGROUND = np.array([5, 5, 10])  # clod::RenderRequest's default background, 8 bits

# The planar DEM: h = A + B x + C y (metres), x0, y0 the north-west sample, spacing D.
A, B, C = 10.0, 0.06, -0.04
X0, Y0, D, ROWS, COLS = -150.0, 120.0, 2.0, 121, 151
LAT0, LON0, H0 = 10.0, 20.0, 0.0
MARS_A, MARS_B = 3396190.0, 3376200.0


def run(*args, check=True, binary=None):
    env = {**os.environ, **NO_LEAK_CHECK}
    p = subprocess.run([binary or BIN, *map(str, args)], capture_output=True, text=True,
                       timeout=300, env=env)
    if check and p.returncode != 0:
        raise AssertionError(f"regolith {' '.join(map(str, args))} failed ({p.returncode}):\n"
                             f"{p.stderr}")
    return p


def read_png(path):
    from PIL import Image  # Debian's python3-pil
    return np.asarray(Image.open(path).convert("RGB")).astype(int)


def terrain_mask(img):
    return np.abs(img - BACKGROUND).sum(axis=2) > 6


def write_store(path, data, x0=X0, y0=Y0, spacing=D):
    rows, cols = data.shape
    with h5py.File(path, "w") as f:
        f.attrs["regolith_store"] = "made by h5py"
        f.attrs["format_version"] = np.array([1, 0], dtype="<i4")
        g = f.create_group("grids/ramp")
        attrs = {
            "format_version": np.array([1, 0], dtype="<i4"), "kind": "dem",
            "rows": np.uint64(rows), "cols": np.uint64(cols), "x0": x0, "y0": y0,
            "spacing": np.array([spacing, spacing]), "units": "m", "sample_type": "float32",
            "scale": 1.0, "offset": 0.0, "nodata": np.float32(-9999.0), "body": "Mars",
            "equatorial_radius": MARS_A, "polar_radius": MARS_B,
            "latitude_type": "planetodetic", "levels": np.uint64(1),
            "patch_shape": np.array([32, 32], dtype="<u8"),
            "placement": "local_tangent_plane", "origin_lat_deg": LAT0,
            "origin_lon_deg": LON0, "origin_height": H0, "heading_deg": 0.0,
        }
        for k, v in attrs.items():
            g.attrs[k] = v
        g.create_dataset("level0", data=data, chunks=(32, 32))


@pytest.fixture(scope="module")
def work(tmp_path_factory):
    return tmp_path_factory.mktemp("render-effects")


@pytest.fixture(scope="module")
def ramp(work):
    r, c = np.mgrid[0:ROWS, 0:COLS]
    x, y = X0 + D * c, Y0 - D * r
    data = (A + B * x + C * y).astype("<f4")
    path = work / "ramp.h5"
    write_store(path, data)
    return path, data


# A wider plane for lat/lon lines: 4 km square at 5 m, centred on the origin.
WIDE_N, WIDE_D = 801, 5.0


@pytest.fixture(scope="module")
def wide(work):
    r, c = np.mgrid[0:WIDE_N, 0:WIDE_N]
    h0 = WIDE_D * (WIDE_N - 1) / 2
    x, y = -h0 + WIDE_D * c, h0 - WIDE_D * r
    path = work / "wide.h5"
    write_store(path, (A + B * x + C * y).astype("<f4"), -h0, h0, WIDE_D)
    return path


@pytest.fixture(scope="module")
def planet(work):
    path = work / "mars.h5"
    run("generate", "mars-planet", "--out", path, "--size", 60, "--patch", 32, "--seed", 5)
    return path


# A straight-down view on the DEM's centre point (the look-at), north up.
W, H, FOV, DIST = 320, 240, 40.0, 300.0
TX, TY = X0 + D * (COLS - 1) / 2, Y0 - D * (ROWS - 1) / 2
DOWN = ["--width", W, "--height", H, "--fov", FOV, "--elevation", 90, "--distance", DIST]


def ground_points(tx=TX, ty=TY, dist=DIST, width=W, height=H, fov=FOV):
    """Ground (x, y, h) of every pixel centre of a straight-down view of the plane, from a
    camera `dist` above the look-at point (tx, ty): ray–plane intersection in double."""
    f = (height / 2) / math.tan(math.radians(fov / 2))
    th = A + B * tx + C * ty
    ex, ey, ez = tx, ty, th + dist
    py, px = np.mgrid[0:height, 0:width] + 0.5
    dx, dy = (px - width / 2) / f, -(py - height / 2) / f  # direction (dx, dy, -1)
    t = (ez - A - B * ex - C * ey) / (1.0 + B * dx + C * dy)
    x, y = ex + t * dx, ey + t * dy
    return x, y, A + B * x + C * y


def ramp_colour(h, lo, hi):
    t = np.clip((h - lo) / (hi - lo), 0.0, 1.0) * 4.0
    k = np.minimum(np.floor(t).astype(int), 3)
    f = (t - k)[..., None]
    return (RAMP[k] * (1 - f) + RAMP[k + 1] * f) * 255.0


def inside_dem(x, y, margin):
    return ((x > X0 + margin) & (x < X0 + D * (COLS - 1) - margin) &
            (y < Y0 - margin) & (y > Y0 - D * (ROWS - 1) + margin))


def legend_panel_mask(shape, json_has_latlon):
    """Pixels the legend panel may cover (top-right corner): left out of colour checks."""
    m = np.zeros(shape[:2], dtype=bool)
    m[:160 if not json_has_latlon else 180, shape[1] - 170:] = True
    return m


# ---- height colours -------------------------------------------------------------------------

def test_height_colours_follow_the_ramp_over_the_given_range(work, ramp):
    path, data = ramp
    out = work / "hc.png"
    lo, hi = 0.0, 40.0  # not the data's range (-3.8 to 23.8 m)
    p = run("render", path, "-o", out, *DOWN, "--effects", "height-colours",
            "--height-range", f"{lo},{hi}")
    assert "effects: height-colours; height colours over [0, 40] m" in p.stdout, p.stdout
    legend = json.loads((work / "hc.png.legend.json").read_text())
    assert legend["heightColours"]["min"] == lo and legend["heightColours"]["max"] == hi
    assert np.allclose(legend["heightColours"]["stops"], RAMP, atol=1e-6)
    img = read_png(out)
    x, y, h = ground_points()
    use = inside_dem(x, y, 2 * D) & ~legend_panel_mask(img.shape, False)
    assert use.sum() > 0.5 * W * H
    err = np.abs(img[use] - ramp_colour(h[use], lo, hi)).max(axis=1)
    # Unlit: the ramp colour itself, to 8-bit rounding and a fraction of a pixel.
    assert np.percentile(err, 99) <= 4, np.percentile(err, 99)
    assert err.max() <= 10, err.max()
    # The same pixels against the data's own range would be far off: the range is used.
    wrong = np.abs(img[use] - ramp_colour(h[use], float(data.min()), float(data.max())))
    assert np.median(wrong.max(axis=1)) > 15


def test_height_colours_default_to_the_grids_height_range(work, ramp):
    path, data = ramp
    out = work / "hc-default.png"
    p = run("render", path, "-o", out, *DOWN, "--effects", "height-colours")
    legend = json.loads((work / "hc-default.png.legend.json").read_text())
    # h5py's min and max of the stored samples (float32), exactly.
    assert legend["heightColours"]["min"] == float(data.min())
    assert legend["heightColours"]["max"] == float(data.max())
    assert f"height colours over [{float(data.min()):.6g}, {float(data.max()):.6g}] m" in p.stdout
    img = read_png(out)
    x, y, h = ground_points()
    use = inside_dem(x, y, 2 * D) & ~legend_panel_mask(img.shape, False)
    err = np.abs(img[use] - ramp_colour(h[use], float(data.min()), float(data.max())))
    assert np.percentile(err.max(axis=1), 99) <= 4


# ---- lat/lon lines --------------------------------------------------------------------------

def lonlat_of(x, y, h):
    """PROJ (cct): tangent-plane metres at (LAT0, LON0, H0) on Mars -> lon, lat degrees."""
    pipeline = (f"+proj=pipeline +step +inv +proj=topocentric +a={MARS_A} +b={MARS_B} "
                f"+lat_0={LAT0} +lon_0={LON0} +h_0={H0} "
                f"+step +inv +proj=cart +a={MARS_A} +b={MARS_B}")
    text = "\n".join(f"{a!r} {b!r} {c!r}" for a, b, c in
                     zip(x.ravel(), y.ravel(), h.ravel())) + "\n"
    p = subprocess.run(["cct", "-d", "12", *pipeline.split()], input=text,
                       capture_output=True, text=True, check=True)
    v = np.array([line.split()[:2] for line in p.stdout.strip().split("\n")], dtype=float)
    return v[:, 0].reshape(x.shape), v[:, 1].reshape(x.shape)


def test_latlon_lines_lie_where_proj_puts_the_meridians_and_parallels(work, wide):
    """Straight down from 1.8 km on a DEM at 10° N, 20° E (5.5 m a pixel): every pixel whose
    ground point PROJ puts within 0.3 pixel of a multiple of 0.003° (178 m) of latitude or
    longitude is a line pixel to within a pixel; no pixel 2.5 pixels from all of them is.
    (The shader's latitude and longitude are float atan() of the float body-fixed position:
    on llvmpipe a few metres off, under a pixel here, not at 1 m a pixel.)"""
    spacing, dist = 0.003, 1800.0
    view = ["--width", W, "--height", H, "--fov", FOV, "--elevation", 90, "--distance", dist]
    bare, lined = work / "ll-bare.png", work / "ll.png"
    run("render", wide, "-o", bare, *view)
    p = run("render", wide, "-o", lined, *view, "--effects", "latlon", "--latlon-spacing",
            spacing)
    assert "lat/lon lines every 0.003°" in p.stdout, p.stdout
    legend = json.loads((work / "ll.png.legend.json").read_text())
    assert legend == {"latLonSpacingDegrees": spacing}
    a, b = read_png(bare), read_png(lined)
    line = np.abs(b - a).sum(axis=2) > 60
    near_line = line.copy()  # a line pixel within one pixel (8-neighbourhood)
    pad = np.pad(line, 1)
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            near_line |= pad[1 + dy:1 + dy + H, 1 + dx:1 + dx + W]
    x, y, h = ground_points(tx=0.0, ty=0.0, dist=dist)
    lon, lat = lonlat_of(x, y, h)
    # Distance of each pixel to the nearest meridian or parallel, in pixels.
    gy_lat, gx_lat = np.gradient(lat)
    gy_lon, gx_lon = np.gradient(lon)
    dlat = np.abs(lat - spacing * np.round(lat / spacing)) / np.hypot(gx_lat, gy_lat)
    dlon = np.abs(lon - spacing * np.round(lon / spacing)) / np.hypot(gx_lon, gy_lon)
    dist_px = np.minimum(dlat, dlon)
    # On the terrain (one stored level: the clipmap draws 254 cells of 5 m around the
    # focus), two pixels in from its edge, outside the legend.
    ground = terrain_mask(a)
    inner = ground.copy()
    for dy in (-2, 0, 2):
        for dx in (-2, 0, 2):
            inner &= np.roll(np.roll(ground, dy, axis=0), dx, axis=1)
    use = inner & ~legend_panel_mask(a.shape, True)
    on, off = use & (dist_px < 0.3), use & (dist_px > 2.5)
    assert on.sum() > 300 and off.sum() > 0.1 * W * H
    assert near_line[on].all(), np.argwhere(on & ~near_line)[:5]  # where PROJ says
    assert not line[off].any(), np.argwhere(line & off)[:5]  # and nowhere else
    # As many meridians crossing the centre row as PROJ counts there.
    row = H // 2
    cols = np.nonzero(inner[row])[0]
    expected = np.count_nonzero(np.diff(np.floor(lon[row, cols] / spacing)))
    runs = np.count_nonzero(np.diff(line[row, cols].astype(int)) == 1)
    assert expected >= 3 and runs == expected, (runs, expected)


def test_adaptive_latlon_spacing_keeps_lines_80_pixels_apart_on_a_placed_dem(work, wide):
    """Without --latlon-spacing: the smallest of 90, 60, …, 0.01, 0.005, … degrees whose
    lines are at least 80 pixels apart at the camera's altitude above the ground (here the
    distance, straight down): worked out here from the focal length and Mars' radius."""
    dist = 1800.0
    out = work / "ll-adaptive.png"
    p = run("render", wide, "-o", out, "--width", W, "--height", H, "--fov", FOV,
            "--elevation", 90, "--distance", dist, "--effects", "latlon")
    assert "lat/lon lines at an adaptive spacing" in p.stdout
    f = (H / 2) / math.tan(math.radians(FOV / 2))
    wanted = 80.0 * math.degrees(dist / f / MARS_A)
    nice = [90, 60, 45, 30, 20, 15, 10, 5, 2, 1] + [m / 10 ** k for k in range(1, 8)
                                                     for m in (5, 2, 1)]
    expected = min(s for s in nice if s >= wanted)
    assert expected == 0.01  # wanted 0.0074°: 0.005° would put lines 54 pixels apart
    legend = json.loads((work / "ll-adaptive.png.legend.json").read_text())
    assert legend == {"latLonSpacingDegrees": expected}


def test_latlon_on_a_planet_draws_lines_only_with_the_effect(work, planet):
    bare, lined = work / "mars-bare.png", work / "mars-ll.png"
    run("render", planet, "-o", bare, "--width", 240, "--height", 180)
    p = run("render", planet, "-o", lined, "--width", 240, "--height", 180, "--effects",
            "latlon", "--latlon-spacing", 30)
    assert "lat/lon lines every 30°" in p.stdout
    a, b = read_png(bare), read_png(lined)
    changed = np.abs(b - a).sum(axis=2) > 60
    # Straight down on (0, 0): the equator and the prime meridian cross the image centre.
    assert changed[88:92, 118:122].any()
    assert changed[90, :].sum() > 40 and changed[:, 120].sum() > 40
    assert not (changed & ~terrain_mask(a) & ~legend_panel_mask(a.shape, True)).any()
    assert not (work / "mars-bare.png.legend.json").exists()


# ---- noise ----------------------------------------------------------------------------------

def test_noise_changes_the_terrain_and_is_deterministic(work, ramp):
    path, _ = ramp
    outs = [work / f"noise-{i}.png" for i in range(2)]
    for o in outs:
        p = run("render", path, "-o", o, *DOWN, "--effects", "noise", "--noise-amplitude",
                0.5, "--noise-wavelength", 8, "--noise-octaves", 3)
    assert "noise 0.5 m, wavelength 8, 3 octaves" in p.stdout
    bare = work / "noise-bare.png"
    run("render", path, "-o", bare, *DOWN)
    a, b = read_png(bare), read_png(outs[0])
    assert outs[0].read_bytes() == outs[1].read_bytes()  # the pattern is tied to the grid
    mask = terrain_mask(a)
    changed = np.abs(b - a).sum(axis=2) > 3
    assert changed[mask].mean() > 0.5
    assert not changed[~mask].any()  # the background stays
    assert not (work / "noise-0.png.legend.json").exists()  # nothing to explain


# ---- tracks ---------------------------------------------------------------------------------

def distance_to_path(x, y, path):
    best = np.full(x.shape, np.inf)
    for (ax, ay), (bx, by) in zip(path[:-1], path[1:]):
        vx, vy = bx - ax, by - ay
        t = np.clip(((x - ax) * vx + (y - ay) * vy) / (vx * vx + vy * vy), 0.0, 1.0)
        best = np.minimum(best, np.hypot(x - ax - t * vx, y - ay - t * vy))
    return best


def test_tracks_darken_the_ground_along_the_traverse_only(work, ramp):
    path, _ = ramp
    waypoints = [(-8.0, -4.0), (6.0, -4.0), (6.0, 7.0)]
    csv = work / "traverse.csv"
    csv.write_text("x,y\n" + "".join(f"{x},{y}\n" for x, y in waypoints))
    view = ["--width", 320, "--height", 240, "--fov", 40, "--elevation", 90, "--distance", 25,
            "--look-at", "0,0"]
    bare, tracked = work / "tracks-bare.png", work / "tracks.png"
    run("render", path, "-o", bare, *view)
    p = run("render", path, "-o", tracked, *view, "--effects", "tracks", "--traverse", csv)
    assert "tracks of 25 m driven" in p.stdout, p.stdout
    a, b = read_png(bare), read_png(tracked)
    diff = b.sum(axis=2) - a.sum(axis=2)
    changed = np.abs(diff) > 6
    x, y, _ = ground_points(tx=0.0, ty=0.0, dist=25.0)
    d = distance_to_path(x, y, waypoints)
    assert changed.sum() > 500
    # Wheels run 1.10 m either side of the path (a corner's front wheel up to 1.56 m off it),
    # ruts 0.20 m either side of a wheel, plus a texel and a pixel.
    assert d[changed].max() < 1.95, d[changed].max()
    assert diff[changed].sum() < 0 and (diff[changed] < 0).mean() > 0.8  # darker
    # Ruts all along: near every metre of the path some pixel changed.
    for (ax, ay), (bx, by) in zip(waypoints[:-1], waypoints[1:]):
        n = int(math.hypot(bx - ax, by - ay))
        for s in np.linspace(0.1, 0.9, n):
            px, py = ax + s * (bx - ax), ay + s * (by - ay)
            assert changed[np.hypot(x - px, y - py) < 1.6].any(), (px, py)


# ---- errors ---------------------------------------------------------------------------------

@pytest.mark.parametrize("args,message", [
    (["--effects", "fog"],
     "render: --effects 'fog' is not an effect, expected one of tracks, height-colours, "
     "latlon, noise"),
    (["--effects", "noise,,latlon"],
     "render: --effects 'noise,,latlon' has an empty name, expected names separated by "
     "commas, each one of tracks, height-colours, latlon, noise"),
    (["--effects", "tracks"],
     "render: --effects tracks needs --traverse FILE (waypoints 'x,y' in the DEM's grid "
     "metres that the rover drives to press its tracks)"),
    (["--traverse", "t.csv"],
     "render: --traverse sets a parameter of tracks, which --effects does not name"),
    (["--height-range", "0,5"],
     "render: --height-range sets a parameter of height-colours, which --effects does not "
     "name"),
    (["--effects", "height-colours", "--latlon-spacing", "1"],
     "render: --latlon-spacing sets a parameter of latlon, which --effects does not name"),
    (["--effects", "latlon", "--noise-octaves", "2"],
     "render: --noise-octaves sets a parameter of noise, which --effects does not name"),
    (["--effects", "height-colours", "--height-range", "5,5"],
     "render: --height-range is 5,5 m, expected low < high (as 32-bit floats)"),
    (["--effects", "height-colours", "--height-range", "7,2"],
     "render: --height-range is 7,2 m, expected low < high (as 32-bit floats)"),
    (["--effects", "latlon", "--latlon-spacing", "1e-9"],
     "render: --latlon-spacing is 1e-09 deg, expected 0 (adapts to the view) or finite and "
     "within [1e-06, 90] deg"),
])
def test_effect_errors_word_for_word(work, ramp, args, message):
    path, _ = ramp
    out = work / "bad.png"
    p = run("render", path, "-o", out, *args, check=False)
    assert p.returncode != 0
    assert p.stderr == f"regolith: error: {message}\n"
    assert not out.exists()


@pytest.mark.parametrize("args,message", [
    (["--effects", "height-colours", "--height-range", "nan,5"],
     "--height-range: Value nan is not a finite number in [-1e+06, 1e+06]"),
    (["--effects", "height-colours", "--height-range", "0,inf"],
     "--height-range: Value inf is not a finite number in [-1e+06, 1e+06]"),
    (["--effects", "latlon", "--latlon-spacing", "91"],
     "--latlon-spacing: Value 91 is not a finite number in [0, 90]"),
    (["--effects", "noise", "--noise-amplitude", "-1"],
     "--noise-amplitude: Value -1 is not a finite number in [0, 10000]"),
    (["--effects", "noise", "--noise-wavelength", "0"],
     "--noise-wavelength: Value 0 is not a finite number in [1e-06, 1e+07]"),
    (["--effects", "noise", "--noise-octaves", "9"],
     "--noise-octaves: Value 9 not in range 1 to 8"),
])
def test_effect_numbers_are_finite_and_in_range(work, ramp, args, message):
    path, _ = ramp
    p = run("render", path, "-o", work / "bad.png", *args, check=False)
    assert p.returncode != 0
    assert p.stderr.startswith(f"regolith: error: {message}\n"), p.stderr


def test_traverse_errors_name_the_file_and_line(work, ramp, planet):
    path, _ = ramp
    bad = work / "bad-traverse.csv"
    bad.write_text("x,y\n1,2\n# comment\n3,four\n")
    p = run("render", path, "-o", work / "bad.png", "--effects", "tracks", "--traverse", bad,
            check=False)
    assert p.stderr == (f"regolith: error: render: {bad}: --traverse line 4 is '3,four', "
                        "expected 'x,y': two finite numbers (grid metres)\n")
    one = work / "one-waypoint.csv"
    one.write_text("1,2\n")
    p = run("render", path, "-o", work / "bad.png", "--effects", "tracks", "--traverse", one,
            check=False)
    assert p.stderr == (f"regolith: error: render: {one}: --traverse waypoints is 1, "
                        "expected at least 2\n")
    missing = work / "no-such.csv"
    p = run("render", path, "-o", work / "bad.png", "--effects", "tracks", "--traverse",
            missing, check=False)
    assert p.stderr == (f"regolith: error: render: {missing}: --traverse file is not readable, "
                        "expected a readable CSV file of waypoints 'x,y' (metres)\n")
    good = work / "good.csv"
    good.write_text("0,0\n5,0\n")
    p = run("render", planet, "-o", work / "bad.png", "--effects", "tracks", "--traverse",
            good, check=False)
    assert p.stderr == (f"regolith: error: render: --effects tracks needs a DEM (a rover "
                        f"drives in metres), and grid 'mars' of {planet} is not one\n")
    assert not (work / "bad.png").exists()


def test_the_legend_beside_the_png_is_always_this_images(work, ramp):
    path, _ = ramp
    out = work / "again.png"
    legend = work / "again.png.legend.json"
    run("render", path, "-o", out, *DOWN, "--effects", "height-colours", "--height-range",
        "0,40")
    assert json.loads(legend.read_text())["heightColours"]["max"] == 40
    run("render", path, "-o", out, *DOWN, "--effects", "height-colours", "--height-range",
        "0,30")
    assert json.loads(legend.read_text())["heightColours"]["max"] == 30
    run("render", path, "-o", out, *DOWN, "--effects", "noise")
    assert not legend.exists()  # no legend for this image: the earlier one is gone


# ---- undeclared effects cost nothing ------------------------------------------------------

def test_without_effects_nothing_changes(work, ramp, planet):
    """No effect declared: no legend beside the PNG, no effects line, and (given a build from
    before the effects options as REGOLITH_REFERENCE_BIN) the same bytes."""
    path, _ = ramp
    cases = [(path, DOWN), (path, ["--width", 200, "--height", 150]),
             (planet, ["--width", 200, "--height", 150]),
             (planet, ["--width", 200, "--height", 150, "--look-at", "20,10", "--distance",
                       800000, "--elevation", 15])]
    for i, (store, args) in enumerate(cases):
        out = work / f"bare-{i}.png"
        p = run("render", store, "-o", out, *args)
        assert "effects:" not in p.stdout
        assert not (work / f"bare-{i}.png.legend.json").exists()
        if REFERENCE_BIN:
            ref = work / f"bare-ref-{i}.png"
            run("render", store, "-o", ref, *args, binary=REFERENCE_BIN)
            assert ref.read_bytes() == out.read_bytes(), (store, args)
