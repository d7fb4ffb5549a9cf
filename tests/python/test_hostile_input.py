"""Hostile input to the regolith Python module (docs/reliability.md, "Catalogue of hostile
input"): a call that writes over its own input, NaN camera numbers, a camera inside the body,
arrays of complex numbers, None or other non-numbers, impossible georeferencing and height
spikes. Every case raises a clear error (ValueError for InvalidArgument) and leaves every
input byte for byte as it was (hashlib is the oracle); rasters are written by GDAL.
"""

import hashlib
import os
import shutil

import numpy as np
import pytest
from osgeo import gdal, osr

import regolith

gdal.UseExceptions()

SAME_FILE = "output is the same file as the input"


def digest(path):
    return hashlib.sha256(open(path, "rb").read()).hexdigest()


def geographic_tif(path, values, geotransform=(137.0, 0.01, 0.0, -4.0, 0.0, -0.01)):
    rows, cols = values.shape
    ds = gdal.GetDriverByName("GTiff").Create(str(path), cols, rows, 1, gdal.GDT_Float64)
    srs = osr.SpatialReference()
    srs.ImportFromProj4("+proj=longlat +R=3396190 +no_defs")
    ds.SetProjection(srs.ExportToWkt())
    ds.SetGeoTransform(list(geotransform))
    ds.GetRasterBand(1).WriteArray(values)
    ds = None
    return path


@pytest.fixture(scope="module")
def dem(tmp_path_factory):
    path = tmp_path_factory.mktemp("hostile") / "v.h5"
    regolith.generate_victoria(path, size=65, spacing=8.0, patch_size=32)
    return regolith.open(path)


@pytest.fixture(scope="module")
def planet(tmp_path_factory):
    path = tmp_path_factory.mktemp("hostile") / "mars.h5"
    regolith.generate_mars(path, rows=36, patch_size=16)
    return regolith.open(path)


# ---- no call writes over its input ----------------------------------------------------------

@pytest.mark.parametrize("how", ["same path", "symlink", "hard link"])
def test_import_raster_refuses_to_write_over_its_raster(tmp_path, how):
    src = geographic_tif(tmp_path / "src.tif", np.full((6, 8), -100.0))
    out = {"same path": src, "symlink": tmp_path / "s.h5", "hard link": tmp_path / "h.h5"}[how]
    if how == "symlink":
        out.symlink_to(src)
    elif how == "hard link":
        os.link(src, out)
    before = digest(src)
    with pytest.raises(ValueError, match=f"store::importRaster\\(\\): .*{SAME_FILE} "):
        regolith.import_raster(src, out)
    assert digest(src) == before


def test_render_flyover_refuses_to_write_a_frame_over_a_store(tmp_path):
    regolith.generate_mars(tmp_path / "mars.h5", rows=36, patch_size=16)
    regolith.generate_victoria(tmp_path / "vic.h5", size=65, spacing=8.0, patch_size=32)
    frames = tmp_path / "frames"
    frames.mkdir()
    (frames / "frame_0001.png").symlink_to(tmp_path / "vic.h5")
    before = digest(tmp_path / "vic.h5")
    with pytest.raises(ValueError, match=f"renderFlyover\\(\\): .*frame_0001.png: {SAME_FILE} "):
        regolith.render_flyover(frames, frames=3, width=32, height=32,
                                mars_store=tmp_path / "mars.h5", victoria_store=tmp_path / "vic.h5")
    assert digest(tmp_path / "vic.h5") == before


# ---- camera numbers -------------------------------------------------------------------------

@pytest.mark.parametrize("kwargs,message", [
    (dict(position=(np.nan, 0.0, 300.0), look_at=(0.0, 0.0, 0.0)),
     "render::renderTerrain(): camera position is (nan, 0, 300), expected finite"),
    (dict(position=(0.0, -900.0, 300.0), look_at=(0.0, np.inf, 0.0)),
     "render::renderTerrain(): camera target is (0, inf, 0), expected finite"),
    (dict(position=(0.0, -900.0, 300.0), heading_deg=np.nan, pitch_deg=-10.0),
     "cameraFromHeadingPitch(): heading is nan deg, expected finite"),
    (dict(position=(0.0, -900.0, 300.0), heading_deg=0.0, pitch_deg=np.nan),
     "cameraFromHeadingPitch(): pitch is nan deg, expected inside (-90, 90)"),
    (dict(position=(0.0, -900.0, 300.0), look_at=(0.0, 0.0, 0.0), fov_deg=np.nan),
     "render::renderTerrain(): field of view is nan deg, expected inside (0, 180)"),
    (dict(position=(0.0, -900.0, 300.0), look_at=(0.0, 0.0, 0.0), near=np.inf),
     "render::renderTerrain(): near plane is inf m, expected finite and > 0"),
    (dict(position=(0.0, -900.0, 300.0), look_at=(0.0, -900.0, 300.0)),
     "render::renderTerrain(): camera target is (0, -900, 300), expected a point other than the camera "
     "position"),
])
def test_render_refuses_bad_camera_numbers(dem, kwargs, message):
    with pytest.raises(ValueError) as e:
        dem.render(width=32, height=32, **kwargs)
    assert str(e.value) == message


def test_render_refuses_a_camera_under_a_dem(dem):
    # The crater floor is about 100 m below the rim; 2000 km below is inside Mars.
    with pytest.raises(ValueError, match=r"render::renderTerrain\(\): camera position is \(0, 0, -2e\+06\) m, "
                       r"[0-9.e+]+ m below the surface, expected above the terrain's surface "
                       r"\(the camera is inside the body\)"):
        dem.render(position=(0.0, 0.0, -2e6), heading_deg=0.0, pitch_deg=-10.0, width=32,
                   height=32)
    h = float(dem.heights(np.array([40.0]), np.array([40.0]))[0])
    with pytest.raises(ValueError, match="below the surface"):
        dem.render(position=(40.0, 40.0, h - 1.0), heading_deg=0.0, pitch_deg=0.0, width=32,
                   height=32)
    # Just above the highest sample of its cell: drawn.
    img = dem.render(position=(40.0, 40.0, h + 30.0), heading_deg=0.0, pitch_deg=-20.0,
                     width=32, height=32)
    assert img.shape == (32, 32, 4)


@pytest.mark.parametrize("position,needle", [
    ((0.0, 0.0, 0.0), "0 m from the body's centre"),
    ((3.0e6, 0.0, 0.0), "m below the surface"),
])
def test_render_refuses_a_camera_inside_a_planet(planet, position, needle):
    with pytest.raises(ValueError, match="camera is inside the body") as e:
        planet.render(position=position, look_at=(3.4e6, 0.0, 0.0), width=32, height=32)
    assert needle in str(e.value)


@pytest.mark.parametrize("kwargs,message", [
    (dict(eye=(np.nan, -300.0, 400.0), look_at=(0.0, 0.0, 0.0)),
     "Pose::lookAt(): eye is nan, -300, 400, expected finite"),
    (dict(eye=(0.0, -300.0, 400.0), look_at=(0.0, 0.0, 0.0), up=(0.0, np.nan, 1.0)),
     "Pose::lookAt(): up is 0, nan, 1, expected finite"),
    (dict(eye=(0.0, -300.0, 400.0), look_at=(0.0, 0.0, 0.0), fov_deg=np.nan),
     "renderSceneView(): field of view is nan deg, expected inside (0, 180)"),
    (dict(eye=(0.0, -300.0, 400.0), look_at=(0.0, 0.0, 0.0), rover=(0.0, np.inf, 0.0)),
     "renderSceneView(): rover is 0, inf, 0 deg, expected a finite grid x, y and heading"),
])
def test_render_scene_refuses_bad_numbers(kwargs, message):
    with pytest.raises(ValueError) as e:
        regolith.render_scene(width=32, height=32, planet_rows=36, dem_size=65, dem_spacing=8.0,
                              clipmap_size=31, **kwargs)
    assert str(e.value).startswith(message), str(e.value)


# ---- arrays that are not real numbers -------------------------------------------------------

BAD_ARRAYS = [
    (np.array([1.0 + 2.0j, 3.0]), "complex128 (its imaginary part would be dropped)"),
    ([None, 1.0], "object (None and other objects are not numbers)"),
    (np.array([1.0, "x"], dtype=object), "object (None and other objects are not numbers)"),
    (np.array([True, False]), "bool"),
    (np.array(["1", "2"]), "<U1"),
]


@pytest.mark.parametrize("bad,dtype", BAD_ARRAYS, ids=["complex", "None", "object", "bool", "str"])
def test_array_calls_refuse_what_is_not_real_numbers(dem, planet, bad, dtype):
    message = (f"regolith: an array argument has dtype {dtype}, expected real numbers "
               "(an integer or floating-point dtype)")
    ok = np.array([0.0, 1.0])
    calls = [
        lambda: dem.heights(bad, ok),
        lambda: dem.heights(ok, bad),
        lambda: dem.surfaces(bad, ok),
        lambda: dem.to_body_fixed(ok, ok, bad),
        lambda: planet.heights(bad, ok),
        lambda: planet.surfaces(ok, bad),
        lambda: regolith.TrackLayer().depth_at(bad, ok),
    ]
    for call in calls:
        with pytest.raises(ValueError) as e:
            call()
        assert str(e.value) == message


def test_real_arrays_of_every_width_still_work(dem):
    x = np.array([0.0, 40.0])
    expect = dem.heights(x, x)
    for dtype in [np.int32, np.uint16, np.float32, np.int64]:
        got = dem.heights(x.astype(dtype), x.astype(dtype))
        assert np.array_equal(got, expect), dtype
    assert np.array_equal(dem.heights([0, 40], [0.0, 40.0]), expect)  # plain lists


# ---- georeferencing and heights an import refuses or reports --------------------------------

def test_import_raster_refuses_impossible_georeferencing(tmp_path):
    src = geographic_tif(tmp_path / "g.tif", np.zeros((4, 4)), (0.0, 1e300, 0.0, 90.0, 0.0, -1.0))
    with pytest.raises(regolith.RasterImportError) as e:
        regolith.import_raster(src, tmp_path / "g.h5")
    assert str(e.value) == (f"store::importRaster(): {src}: pixel width is 1e+300 deg, expected at "
                            "most 360 deg (one pixel cannot be larger than the body)")
    assert not (tmp_path / "g.h5").exists()


def test_import_raster_reports_or_refuses_implausible_heights(tmp_path):
    values = np.full((6, 8), -2500.0)
    values[1, 2] = 1e30
    src = geographic_tif(tmp_path / "spike.tif", values)
    rep = regolith.import_raster(src, tmp_path / "spike.h5")
    assert rep["implausible_samples"] == 1
    assert rep["plausible_limit"] == 339619.0
    with pytest.raises(regolith.RasterImportError) as e:
        regolith.import_raster(src, tmp_path / "strict.h5", strict=True)
    assert str(e.value).startswith(
        f"store::importRaster(): {src}: sample at row 1, col 2 is 1e+30 m, expected within "
        "+-339619 m")
    assert not (tmp_path / "strict.h5").exists()
    clean = regolith.import_raster(geographic_tif(tmp_path / "c.tif", np.full((6, 8), 10.0)),
                                   tmp_path / "c.h5")
    assert clean["implausible_samples"] == 0


def test_open_names_a_symlink_loop(tmp_path):
    (tmp_path / "a.h5").symlink_to(tmp_path / "b.h5")
    (tmp_path / "b.h5").symlink_to(tmp_path / "a.h5")
    with pytest.raises(regolith.StoreError, match="symlink loop"):
        regolith.open(tmp_path / "a.h5")
    with pytest.raises(regolith.RasterImportError, match="symlink loop"):
        regolith.import_raster(tmp_path / "a.h5", tmp_path / "out.h5")
