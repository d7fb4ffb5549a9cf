"""regolith.load_scene() and SceneFile.render() (docs/scene-format.md, docs/python.md).

Oracles: the scene's geometry (straight up from the rover only the clear colour shows;
straight down at the DEM the unlit height-colour ramp of the DEM's height there, the height
taken from the generator's samples through the scene's own file), and the error format.
"""

import json

import numpy as np
import pytest

import regolith

SKY = np.array([5, 5, 10])  # the clear colour (0.02, 0.02, 0.04) in 8 bits

SCENE = {
    "version": 1,
    "bodies": [{"name": "mars", "heights": [{"generate": "mars-planet", "rows": 90, "seed": 2}]}],
    "dems": [{"name": "crater", "body": "mars",
              "heights": {"generate": "victoria", "size": 201, "spacing": 4, "seed": 2},
              "placement": {"lat": -2.05, "lon": -5.5, "height": "surface"},
              "effects": {"heightColours": {"min": -80, "max": 20}}}],
    "objects": [{"name": "rover", "dem": "crater", "pose": {"x": 0, "y": -360, "heading": 0}}],
    "cameras": [
        {"name": "floor", "frame": "crater", "eye": [0, 0, 150], "lookAt": [0, 0, 0],
         "up": [0, 1, 0], "width": 96, "height": 64, "near": 1},
        {"name": "up", "frame": "rover", "eye": [0, 0, 3], "lookAt": [0, 0, 100],
         "up": [1, 0, 0], "width": 80, "height": 48},
    ],
}


@pytest.fixture
def path(tmp_path):
    p = tmp_path / "scene.json"
    p.write_text(json.dumps(SCENE))
    return p


def test_load_scene_lists_cameras_and_declared_effects(path):
    s = regolith.load_scene(path)
    assert s.cameras == ["floor", "up"]
    info = json.loads(s.info)
    assert info["dems"][0]["effects"] == ["heightColours"]
    assert info["bodies"][0]["effects"] == []


def test_render_returns_the_cameras_image(path):
    s = regolith.load_scene(str(path))
    up = s.render(camera="up")
    assert up.shape == (48, 80, 4) and up.dtype == np.uint8
    assert (up[:, :, :3] == SKY).all()
    floor = s.render(camera="floor")
    assert floor.shape == (64, 96, 4)
    # The crater's floor lies 50 to 75 m below the plains: the ramp's first stops (blue to
    # teal, -80 m to -55 m), far from the planet's reddish albedo and from the sky.
    r, g, b = (int(v) for v in floor[32, 48, :3])
    assert b > r + 40 and b > 80, (r, g, b)


def test_unknown_camera_and_bad_files_are_value_errors(path, tmp_path):
    s = regolith.load_scene(path)
    with pytest.raises(ValueError, match="no camera named 'rovr', expected one of: floor, up"):
        s.render(camera="rovr")
    with pytest.raises(ValueError, match="camera=NAME is needed"):
        s.render()
    bad = dict(SCENE, cameras=[dict(SCENE["cameras"][0], fovY=190)])
    p = tmp_path / "bad.json"
    p.write_text(json.dumps(bad))
    with pytest.raises(ValueError, match=r"bad.json: /cameras/0/fovY: 190 is not in \(0, 180\)"):
        regolith.load_scene(p)
