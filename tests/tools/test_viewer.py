"""`regolith view` driven by scripts in a real GLFW window on a virtual X server (ctest runs
this file under xvfb-run). Checked against outside oracles: a brute-force ray/terrain
intersection in double over the store's own samples read with h5py, the projection of a
fixed world point before and after a focus switch, and the pixels of the screenshots."""
import json
import math
import os
import re
import subprocess
from pathlib import Path

import h5py
import numpy as np
import pytest

BIN = os.environ["REGOLITH_BIN"]
W, H = 1280, 720


def run(*args, timeout=600):
    p = subprocess.run([BIN, *map(str, args)], capture_output=True, text=True, timeout=timeout)
    assert p.returncode == 0, p.stdout + p.stderr
    return p.stdout


def read_png(path):
    from PIL import Image  # Debian's python3-pil
    return np.asarray(Image.open(path).convert("RGB")).astype(int)


def below_hud(img):
    """The image without the HUD's box (top-left): the bottom two thirds."""
    return img[img.shape[0] // 3:]


@pytest.fixture(scope="module")
def work(tmp_path_factory):
    return tmp_path_factory.mktemp("viewer")


@pytest.fixture(scope="module")
def planet(work):
    path = work / "mars.h5"
    run("generate", "mars-planet", "--out", path, "--size", 720, "--threads", 1)
    return path


def bilinear_planet(f, lon, lat):
    """Height at (lon, lat) from level 0 of the store's grid 'mars' (h5py), bilinear between
    sample centres, longitude wrapping."""
    g = f["grids/mars"]
    x0, y0 = float(g.attrs["x0"]), float(g.attrs["y0"])
    dx, dy = (float(v) for v in g.attrs["spacing"])
    data = g["level0"]
    rows, cols = data.shape
    c = (lon - x0) / dx
    r = (y0 - lat) / dy
    r = min(max(r, 0.0), rows - 1.000001)
    c0, r0 = math.floor(c), math.floor(r)
    fc, fr = c - c0, r - r0
    cs = [(c0 % cols), ((c0 + 1) % cols)]
    top = data[r0, cs].astype(np.float64)
    bot = data[r0 + 1, cs].astype(np.float64)
    return (1 - fr) * ((1 - fc) * top[0] + fc * top[1]) + fr * ((1 - fc) * bot[0] + fc * bot[1])


def ray_hit(f, eye, direction, radius):
    """The first point where the ray meets the bilinear surface radius + h(lat, lon): march in
    steps of 200 m from where it enters the highest shell, then bisect (double)."""
    eye, d = np.array(eye), np.array(direction) / np.linalg.norm(direction)

    def above(t):
        p = eye + t * d
        r = np.linalg.norm(p)
        lat = math.degrees(math.asin(p[2] / r))
        lon = math.degrees(math.atan2(p[1], p[0]))
        return r - (radius + bilinear_planet(f, lon, lat))

    top = radius + 30e3  # above any generated relief
    b = np.dot(eye, d)
    c = np.dot(eye, eye) - top * top
    t = -b - math.sqrt(b * b - c)
    step = 200.0
    while above(t + step) > 0:
        t += step
    lo, hi = t, t + step
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if above(mid) > 0 else (lo, mid)
    p = eye + lo * d
    r = np.linalg.norm(p)
    return (math.degrees(math.atan2(p[1], p[0])), math.degrees(math.asin(p[2] / r)), r - radius)


PICK = re.compile(r"pick (\d+) (\d+): lon (\S+) lat (\S+) height (\S+) m dataset (\S+)")
RAY = re.compile(r"pick ray in the body frame: eye (\S+) (\S+) (\S+) dir (\S+) (\S+) (\S+)")


def test_store_opens_framed_and_a_pick_matches_the_store(work, planet):
    """A bare planet store opens with the planet whole in view (a disc of terrain inside the
    image, space around it); after zooming in, a pick at the centre gives the point where a
    brute-force ray/terrain intersection over the store's samples (h5py, double) finds it,
    and height colours appear when their effect is toggled on."""
    script = work / "store.txt"
    script.write_text(f"""# open, look, zoom in, pick, toggle height colours
wait 2
screenshot {work}/open.png
scroll 14 640 360
wait 1
pick 640 360
pick 500 300
screenshot {work}/zoomed.png
key 1
wait 1
screenshot {work}/colours.png
""")
    out = run("view", planet, "--script", script)
    img = read_png(work / "open.png")
    terrain = np.abs(img - np.array([5, 5, 10])).sum(axis=2) > 12
    lower = below_hud(terrain)
    # The planet whole: space on all four sides of the lower image, terrain in the middle.
    assert lower[:, :40].mean() < 0.02 and lower[:, -40:].mean() < 0.02, "planet not framed"
    assert lower[-20:, :].mean() < 0.02
    assert terrain[H // 2 - 50:H // 2 + 50, W // 2 - 50:W // 2 + 50].mean() > 0.99
    # Lit: brightness varies over the disc (relief shading, not a flat colour).
    grey = img.sum(axis=2)[terrain]
    assert grey.std() > 20

    picks = PICK.findall(out)
    rays = RAY.findall(out)
    assert len(picks) == 2 and len(rays) == 2, out
    with h5py.File(planet, "r") as f:
        radius = float(f["grids/mars"].attrs["equatorial_radius"])
        for (px, py, lon, lat, h, dataset), ray in zip(picks, rays):
            lon, lat, h = float(lon), float(lat), float(h)
            assert dataset == "mars"
            vals = [float(v) for v in ray]
            hit_lon, hit_lat, hit_h = ray_hit(f, vals[:3], vals[3:], radius)
            # The GPU draws the clipmap's triangles between level-0 samples, the oracle the
            # bilinear surface between the same samples: they differ by a fraction of the
            # local relief (7-16 m measured here), which moves the hit along a ray seen from
            # 60-75 degrees above the horizon by about as much (4-6 m measured).
            dist = radius * math.radians(math.hypot((hit_lon - lon) * math.cos(math.radians(lat)),
                                                    hit_lat - lat))
            assert dist < 100.0, (px, py, lon, lat, hit_lon, hit_lat)
            assert abs(h - hit_h) < 60.0, (h, hit_h)
            assert abs(h - bilinear_planet(f, lon, lat)) < 60.0

    # Height colours: the ramp's blue and green stops appear where the lit albedo was.
    before, after = read_png(work / "zoomed.png"), read_png(work / "colours.png")

    def ramp_share(img):
        lower = below_hud(img)
        blue_or_green = (lower[:, :, 2] > lower[:, :, 0] + 30) | (lower[:, :, 1] > lower[:, :, 0] + 30)
        return blue_or_green.mean()

    assert ramp_share(before) < 0.01
    assert ramp_share(after) > 0.3
    assert "effect mars heightColours on: pipeline rebuilt" in out


FOCUS = re.compile(r"focus (\S+) -> (\S+) \(viewport (\d)\): the \S+ origin projects to "
                   r"\((\S+), (\S+)\) px before, \((\S+), (\S+)\) px after; the \S+ origin to "
                   r"\((\S+), (\S+)\) px before, \((\S+), (\S+)\) px after")


def test_demo_focus_switch_toggle_and_pick(work):
    """The demo scene opens split (Mars whole, Victoria at 35 degrees). In the right viewport
    a focus switch re-roots without a jump (a fixed world point projects to the same pixel,
    and the image stays the same), Victoria's height colours toggle on, and a pick at the
    centre names Victoria at its site on Mars."""
    script = work / "demo.txt"
    script.write_text(f"""wait 2
move 960 400
screenshot {work}/demo-before.png
key TAB
wait 1
screenshot {work}/demo-after.png
key 4
wait 1
screenshot {work}/demo-colours.png
pick 960 360
key C
wait 1
screenshot {work}/demo-camera.png
""")
    out = run("view", "--demo", "--script", script)
    switches = FOCUS.findall(out)
    assert len(switches) == 1, out
    old, new, viewport, *xy = switches[0]
    assert (old, new, viewport) == ("victoria", "second_dem", "2")
    obx, oby, oax, oay, nbx, nby, nax, nay = map(float, xy)
    # Victoria's origin (the crater's centre) is on screen in the right viewport.
    assert 0 <= obx < W // 2 and 0 <= oby < H
    for before, after in ((obx, oax), (oby, oay), (nbx, nax), (nby, nay)):
        assert abs(before - after) < 1e-3

    before, after = read_png(work / "demo-before.png"), read_png(work / "demo-after.png")
    right = slice(W // 2 + 2, W)
    changed = np.abs(below_hud(before)[:, right] - below_hud(after)[:, right]).sum(axis=2) > 30
    assert changed.mean() < 0.005, changed.mean()
    # Both viewports show terrain.
    for half in (slice(0, W // 2 - 2), right):
        t = np.abs(below_hud(before)[:, half] - np.array([5, 5, 10])).sum(axis=2) > 12
        assert t.mean() > 0.2

    colours = read_png(work / "demo-colours.png")
    blue = lambda img: (below_hud(img)[:, right][:, :, 2] > below_hud(img)[:, right][:, :, 0] + 30).mean()
    assert blue(after) < 0.01 and blue(colours) > 0.05, (blue(after), blue(colours))
    assert "effect victoria heightColours on: pipeline rebuilt" in out

    picks = PICK.findall(out)
    assert len(picks) == 1, out
    _, _, lon, lat, h, dataset = picks[0]
    assert dataset == "victoria"
    # Victoria's site (scenegraph::PaperSceneLayout): lon -5.5, lat -2.05, a 1.2 km DEM.
    assert abs(float(lon) + 5.5) < 0.03 and abs(float(lat) + 2.05) < 0.03

    # C: the right viewport shows the scene's first camera (the orbit camera, 20 km above
    # Victoria looking down), the left one is unchanged.
    camera = read_png(work / "demo-camera.png")
    diff = np.abs(below_hud(camera) - below_hud(colours)).sum(axis=2) > 30
    assert diff[:, right].mean() > 0.3 and diff[:, :W // 2 - 2].mean() < 0.005


SCENE_FILE = {
    "version": 1,
    "bodies": [{"name": "mars", "heights": [{"generate": "mars-planet", "rows": 180, "seed": 2}]}],
    "dems": [{"name": "crater", "body": "mars",
              "heights": {"generate": "victoria", "size": 201, "spacing": 4, "seed": 2},
              "placement": {"lat": -2.05, "lon": -5.5, "height": "surface"},
              "colour": [0.2, 0.8, 0.3],
              "effects": {"heightColours": {"min": -80, "max": 20}}}],
    "objects": [{"name": "rover", "dem": "crater", "pose": {"x": 0, "y": -360, "heading": 0}}],
    "cameras": [{"name": "down", "frame": "crater", "eye": [-300, 300, 150],
                 "lookAt": [-300, 300, 0], "up": [0, 1, 0], "width": 96, "height": 64,
                 "near": 1}],
    "light": {"frame": "crater", "elevation": 45, "azimuth": 90},
}


def test_scene_file_opens_split_toggles_its_declared_effect_and_picks_its_dem(work):
    """A scene file (docs/scene-format.md) opens as scene::Scene builds it: the body whole on
    the left, its DEM from above at 35 degrees on the right. The DEM's declared height
    colours toggle on (the only effect the file declares, so the only toggle), and a pick at
    the right viewport's centre names the DEM at the site the file places it."""
    scene = work / "scene.json"
    scene.write_text(json.dumps(SCENE_FILE))
    script = work / "scene-script.txt"
    script.write_text(f"""wait 2
screenshot {work}/scene-before.png
key 1
wait 1
screenshot {work}/scene-colours.png
pick 960 360
""")
    out = run("view", scene, "--script", script)
    assert "effect crater heightColours on: pipeline rebuilt" in out, out
    before, colours = read_png(work / "scene-before.png"), read_png(work / "scene-colours.png")
    right = slice(W // 2 + 2, W)
    for half in (slice(0, W // 2 - 2), right):  # terrain in both viewports
        t = np.abs(below_hud(before)[:, half] - np.array([5, 5, 10])).sum(axis=2) > 12
        assert t.mean() > 0.2
    blue = lambda img: (below_hud(img)[:, right][:, :, 2] > below_hud(img)[:, right][:, :, 0] + 30).mean()
    assert blue(before) < 0.01 and blue(colours) > 0.05, (blue(before), blue(colours))
    picks = PICK.findall(out)
    assert len(picks) == 1, out
    _, _, lon, lat, h, dataset = picks[0]
    assert dataset == "crater"
    assert abs(float(lon) + 5.5) < 0.03 and abs(float(lat) + 2.05) < 0.03


def test_no_display_is_a_clear_error(planet):
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    p = subprocess.run([BIN, "view", str(planet)], capture_output=True, text=True, timeout=120,
                       env=env)
    assert p.returncode != 0
    assert "regolith: error: gl::Window(): glfwInit() failed" in p.stderr
    assert "run under xvfb-run for a virtual one" in p.stderr


def test_bad_script_line_is_named(work, planet):
    script = work / "bad.txt"
    script.write_text("wait 1\njump 3\n")
    p = subprocess.run([BIN, "view", str(planet), "--script", str(script)], capture_output=True,
                       text=True, timeout=120)
    assert p.returncode != 0
    assert f"view: --script {script}:2: 'jump 3': expected one of wait, key, drag, scroll, move, " \
           "pick, screenshot, quit" in p.stderr


PICK_XY = re.compile(r"pick (\d+) (\d+): x (\S+) y (\S+) height (\S+) m dataset (\S+)")


def test_dem_store_opens_on_the_dem_and_picks_match_its_samples(work):
    """A DEM store opens with the DEM from above at an angle, the whole grid drawn (the
    clipmap reaches across it); picks give grid x, y and the height there, which must be the
    bilinear height of the store's level-0 samples (h5py) at that x, y."""
    path = work / "victoria.h5"
    run("generate", "victoria", "--out", path, "--size", 401)
    script = work / "dem.txt"
    script.write_text(f"""wait 2
screenshot {work}/dem-open.png
pick 640 400
pick 400 500
pick 900 300
drag 640 400 740 380
key F
key W
wait 1
screenshot {work}/dem-moved.png
""")
    out = run("view", path, "--script", script)
    img = read_png(work / "dem-open.png")
    terrain = np.abs(img - np.array([5, 5, 10])).sum(axis=2) > 12
    assert terrain[H // 2 - 100:H // 2 + 100, W // 2 - 100:W // 2 + 100].mean() > 0.99
    moved = read_png(work / "dem-moved.png")
    assert (np.abs(below_hud(moved) - below_hud(img)).sum(axis=2) > 30).mean() > 0.2
    picks = PICK_XY.findall(out)
    assert len(picks) == 3, out
    with h5py.File(path, "r") as f:
        g = f["grids/victoria"]
        x0, y0 = float(g.attrs["x0"]), float(g.attrs["y0"])
        dx, dy = (float(v) for v in g.attrs["spacing"])
        data = g["level0"][...].astype(np.float64)
    for _, _, x, y, h, dataset in picks:
        x, y, h = float(x), float(y), float(h)
        assert dataset == "victoria"
        c, r = (x - x0) / dx, (y0 - y) / dy
        c0, r0 = int(c), int(r)
        fc, fr = c - c0, r - r0
        bil = ((1 - fr) * ((1 - fc) * data[r0, c0] + fc * data[r0, c0 + 1]) +
               fr * ((1 - fc) * data[r0 + 1, c0] + fc * data[r0 + 1, c0 + 1]))
        # A triangle against the bilinear patch between the same four samples differs by at
        # most fc*fr*|h00 - h01 - h10 + h11| <= 0.25 * 2 * (max - min), plus the depth
        # buffer's float precision at ~500 m (a few mm).
        cell = data[r0:r0 + 2, c0:c0 + 2]
        assert abs(h - bil) <= 0.5 * (cell.max() - cell.min()) + 0.01, (x, y, h, bil)


def test_help_names_the_options():
    p = subprocess.run([BIN, "view", "--help"], capture_output=True, text=True, timeout=60)
    assert p.returncode == 0
    for word in ("--demo", "--script", "--grid", "--cache-mb", "--clipmap-size", "Example"):
        assert word in p.stdout, word
