"""pytest suite of the regolith Python module (bindings/python), run by ctest.

Outside oracles: h5py reads the stores' samples and attributes directly
(docs/store-format.md), GDAL writes the rasters that are imported, and analytic planes give
exact heights and normals. The module is found through PYTHONPATH (ctest sets it to the
build's bindings/python/package).
"""

import math
import threading

import h5py
import numpy as np
import pytest
from osgeo import gdal

import regolith

gdal.UseExceptions()


@pytest.fixture(scope="module")
def victoria(tmp_path_factory):
    path = tmp_path_factory.mktemp("victoria") / "victoria.h5"
    regolith.generate_victoria(path, size=302, spacing=4.0, patch_size=64)
    return path


@pytest.fixture(scope="module")
def plane_tif(tmp_path_factory):
    """A GeoTIFF of h = 0.25·x − 0.125·y + 10 on a 1 m grid (x east, y north), written by GDAL."""
    path = tmp_path_factory.mktemp("plane") / "plane.tif"
    rows, cols = 120, 160
    x0, y0 = 500.0, 2000.0  # top-left corner of the top-left pixel
    ds = gdal.GetDriverByName("GTiff").Create(str(path), cols, rows, 1, gdal.GDT_Float32)
    ds.SetGeoTransform((x0, 1.0, 0.0, y0, 0.0, -1.0))
    srs = (
        'PROJCS["Mars equirectangular",GEOGCS["Mars",DATUM["Mars",SPHEROID["Mars",3396190,0]],'
        'PRIMEM["Reference meridian",0],UNIT["degree",0.0174532925199433]],'
        'PROJECTION["Equirectangular"],PARAMETER["standard_parallel_1",0],'
        'PARAMETER["central_meridian",0],PARAMETER["false_easting",0],'
        'PARAMETER["false_northing",0],UNIT["metre",1]]'
    )
    ds.SetProjection(srs)
    c, r = np.meshgrid(np.arange(cols), np.arange(rows))
    x = x0 + 0.5 + c
    y = y0 - 0.5 - r
    ds.GetRasterBand(1).WriteArray((0.25 * x - 0.125 * y + 10.0).astype(np.float32))
    ds = None
    return path


def level0(path, grid):
    with h5py.File(path, "r") as f:
        g = f["grids"][grid]
        return g["level0"][...], dict(g.attrs)


# ---- stores and grids -----------------------------------------------------------------------


def test_store_lists_its_grids_as_h5py_reads_them(victoria):
    s = regolith.Store(victoria)
    with h5py.File(victoria, "r") as f:
        names = sorted(f["grids"].keys())
        attrs = dict(f["grids"]["victoria"].attrs)
    assert s.grid_names() == names == ["victoria"]
    info = s.grid("victoria")
    assert info.kind == "dem"
    assert (info.rows, info.cols) == (int(attrs["rows"]), int(attrs["cols"])) == (302, 302)
    assert info.x0 == pytest.approx(float(attrs["x0"]), abs=0) and info.y0 == float(attrs["y0"])
    assert info.levels == int(attrs["levels"])
    assert info.extent == (info.x0 - 2.0, info.x0 + 301 * 4.0 + 2.0,
                           info.y0 - 301 * 4.0 - 2.0, info.y0 + 2.0)
    assert list(s.grids) == ["victoria"] and s.grids["victoria"].rows == 302


def test_a_missing_store_raises_store_error_with_the_path(tmp_path):
    with pytest.raises(regolith.StoreError, match=r"store::open\(\): .*nope\.h5") as e:
        regolith.Store(tmp_path / "nope.h5")
    assert isinstance(e.value, OSError) and isinstance(e.value, regolith.Error)
    with pytest.raises(regolith.StoreError, match="nope.h5: no such file"):
        regolith.open(tmp_path / "nope.h5", grid="victoria")


def test_an_unknown_grid_raises_store_error(victoria):
    with pytest.raises(regolith.StoreError, match="'nope'"):
        regolith.open(victoria, grid="nope")


# ---- batch queries --------------------------------------------------------------------------


def test_heights_at_sample_centres_are_the_stored_samples(victoria):
    samples, attrs = level0(victoria, "victoria")
    dem = regolith.open(victoria)
    rng = np.random.default_rng(7)
    r = rng.integers(0, 302, 5000)
    c = rng.integers(0, 302, 5000)
    x = float(attrs["x0"]) + 4.0 * c
    y = float(attrs["y0"]) - 4.0 * r
    h = dem.heights(x, y)
    np.testing.assert_array_equal(h, samples[r, c].astype(np.float64))
    # Midway between two samples of a row, bilinear is their mean.
    inner = c < 301
    hm = dem.heights(x[inner] + 2.0, y[inner])
    expect = 0.5 * (samples[r[inner], c[inner]].astype(np.float64)
                    + samples[r[inner], c[inner] + 1].astype(np.float64))
    np.testing.assert_allclose(hm, expect, rtol=0, atol=1e-9)


def test_batches_keep_their_shape_and_agree_with_single_queries(victoria):
    dem = regolith.open(victoria)
    x = np.linspace(-500.0, 500.0, 24).reshape(4, 6)
    y = np.linspace(300.0, -300.0, 24).reshape(4, 6)
    h, n = dem.surfaces(x, y, interp="bicubic")
    assert h.shape == (4, 6) and n.shape == (4, 6, 3) and h.dtype == np.float64
    single = np.array([dem.height(a, b, interp="bicubic") for a, b in zip(x.ravel(), y.ravel())])
    np.testing.assert_array_equal(h.ravel(), single)
    np.testing.assert_allclose(np.linalg.norm(n, axis=-1), 1.0, atol=1e-12)
    # float32 and strided inputs are converted, not rejected.
    h32 = dem.heights(x.astype(np.float32)[:, ::2], y.astype(np.float32)[:, ::2])
    np.testing.assert_array_equal(
        h32, dem.heights(x.astype(np.float32)[:, ::2].astype(np.float64),
                         y.astype(np.float32)[:, ::2].astype(np.float64)))


def test_out_arrays_receive_the_results(victoria):
    dem = regolith.open(victoria)
    x = np.linspace(-500.0, 500.0, 1000)
    y = np.linspace(-200.0, 300.0, 1000)
    h, n = dem.surfaces(x, y)
    oh, on = np.full(1000, -1.0), np.full((1000, 3), -1.0)
    rh, rn = dem.surfaces(x, y, out=(oh, on))
    assert rh is oh and rn is on
    np.testing.assert_array_equal(oh, h)
    np.testing.assert_array_equal(on, n)
    o = np.empty(1000)
    assert dem.heights(x, y, out=o) is o
    np.testing.assert_array_equal(o, h)
    with pytest.raises(regolith.InvalidArgument, match=r"out has shape \(999,\), expected"):
        dem.heights(x, y, out=np.empty(999))
    with pytest.raises(regolith.InvalidArgument, match="out must be a float64"):
        dem.heights(x, y, out=np.empty(1000, dtype=np.float32))
    with pytest.raises(regolith.InvalidArgument, match="C-contiguous"):
        dem.heights(x, y, out=np.empty(2000)[::2])


def test_outside_points_are_nan_with_a_status(victoria):
    dem = regolith.open(victoria)
    h, st = dem.heights(np.array([0.0, 605.0, -1e6]), np.array([0.0, 0.0, 0.0]), status=True)
    assert not math.isnan(h[0]) and math.isnan(h[1]) and math.isnan(h[2])
    assert st.tolist() == [regolith.STATUS_OK, regolith.STATUS_OUTSIDE, regolith.STATUS_OUTSIDE]
    h, n, st = dem.surfaces(np.array([605.0]), np.array([0.0]), status=True)
    assert math.isnan(h[0]) and np.isnan(n).all() and st[0] == regolith.STATUS_OUTSIDE


def test_height_next_to_a_hole_is_valid_and_the_normal_has_its_own_status(tmp_path):
    """Issue 16: a valid height next to a hole stays valid (status), its normal comes from a
    one-sided stencil (normal_status); the corners of the reported extent are inside."""
    path = tmp_path / "holes.tif"
    rows, cols = 40, 50
    x0, y0 = 500.0, 2000.0
    ds = gdal.GetDriverByName("GTiff").Create(str(path), cols, rows, 1, gdal.GDT_Float32)
    ds.SetGeoTransform((x0, 1.0, 0.0, y0, 0.0, -1.0))
    ds.SetProjection((
        'PROJCS["Mars equirectangular",GEOGCS["Mars",DATUM["Mars",SPHEROID["Mars",3396190,0]],'
        'PRIMEM["Reference meridian",0],UNIT["degree",0.0174532925199433]],'
        'PROJECTION["Equirectangular"],PARAMETER["standard_parallel_1",0],'
        'PARAMETER["central_meridian",0],PARAMETER["false_easting",0],'
        'PARAMETER["false_northing",0],UNIT["metre",1]]'))
    c, r = np.meshgrid(np.arange(cols), np.arange(rows))
    x, y = x0 + 0.5 + c, y0 - 0.5 - r
    values = (0.25 * x - 0.5 * y + 10.0).astype(np.float32)  # exact in float32
    values[20, 30] = -9999.0
    band = ds.GetRasterBand(1)
    band.SetNoDataValue(-9999.0)
    band.WriteArray(values)
    ds = None
    out = tmp_path / "holes.h5"
    regolith.import_raster(path, out, grid="holes", patch_size=16)
    dem = regolith.open(out)
    cells = [(19, 30), (21, 30), (20, 29), (20, 31), (20, 30)]
    qx = np.array([x0 + 0.5 + cc for _, cc in cells])
    qy = np.array([y0 - 0.5 - rr for rr, _ in cells])
    expect = np.array([-0.25, 0.5, 1.0]) / math.sqrt(0.25**2 + 0.5**2 + 1.0)
    for interp in ["nearest", "bilinear", "bicubic"]:
        h, n, st, nst = dem.surfaces(qx, qy, interp=interp, status=True, normal_status=True)
        assert st.tolist() == [regolith.STATUS_OK] * 4 + [regolith.STATUS_NODATA], interp
        assert nst.tolist() == [regolith.STATUS_OK] * 4 + [regolith.STATUS_NODATA], interp
        assert h[:4].tolist() == [float(values[rr, cc]) for rr, cc in cells[:4]]
        np.testing.assert_allclose(n[:4], np.broadcast_to(expect, (4, 3)), rtol=0, atol=1e-12)
        assert math.isnan(h[4]) and np.isnan(n[4]).all()
        # normal_status alone comes right after the normals.
        h2, n2, nst2 = dem.surfaces(qx, qy, interp=interp, normal_status=True)
        assert nst2.tolist() == nst.tolist()
    # The corners of the extent, exactly as reported, are inside.
    w, e, s, nn = dem.extent
    h, st = dem.heights(np.array([w, e, w, e]), np.array([s, s, nn, nn]), status=True)
    assert st.tolist() == [regolith.STATUS_OK] * 4
    assert regolith.STATUS_UNMAPPABLE == 3


def test_bad_query_input_raises_with_the_cpp_message(victoria):
    dem = regolith.open(victoria)
    with pytest.raises(regolith.InvalidArgument, match=r"TopoDem::heights\(\): xs\[1\] is nan"):
        dem.heights(np.array([0.0, np.nan]), np.array([0.0, 0.0]))
    with pytest.raises(ValueError, match=r"Dem.heights\(\): x has shape \(3,\) and y has shape "
                                         r"\(2,\), expected the same shape"):
        dem.heights(np.zeros(3), np.zeros(2))
    with pytest.raises(regolith.InvalidArgument, match="interpolation 'cubic' is unknown"):
        dem.heights(np.zeros(1), np.zeros(1), interp="cubic")


def test_batch_queries_run_from_several_threads(victoria):
    dem = regolith.open(victoria)
    x = np.random.default_rng(3).uniform(-600, 600, 200_000)
    y = np.random.default_rng(4).uniform(-600, 600, 200_000)
    expect = dem.heights(x, y)
    out = [None] * 4

    def work(i):
        out[i] = dem.heights(x, y)

    threads = [threading.Thread(target=work, args=(i,)) for i in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for o in out:
        np.testing.assert_array_equal(o, expect)


def test_cache_statistics_and_budget(victoria):
    cache = regolith.Cache(3 * (64 * 64 * 4 + 1024), policy="hitcount")
    dem = regolith.open(victoria, cache=cache)
    assert dem.cache is cache and cache.policy == "hitcount"
    dem.heights(np.linspace(-600, 600, 10_000), np.linspace(-600, 600, 10_000))
    s = cache.stats()
    assert s["loads"] >= 5 and s["evictions"] > 0  # the diagonal crosses 5 patch rows
    assert s["resident_bytes"] <= s["capacity_bytes"] == 3 * (64 * 64 * 4 + 1024)
    assert regolith.Store(victoria).counters()["reads"] == 0  # a new Store has read nothing
    with pytest.raises(regolith.InvalidArgument, match="capacity_bytes is 0"):
        regolith.Cache(0)


# ---- import and generate --------------------------------------------------------------------


def test_import_raster_gives_exact_plane_heights_and_normals(plane_tif, tmp_path):
    out = tmp_path / "plane.h5"
    rep = regolith.import_raster(plane_tif, out, grid="plane", patch_size=64)
    assert rep["driver"] == "GTiff" and (rep["rows"], rep["cols"]) == (120, 160)
    dem = regolith.open(out)
    assert dem.extent == (500.0, 660.0, 1880.0, 2000.0)
    rng = np.random.default_rng(1)
    x = rng.uniform(501.0, 659.0, 1000)
    y = rng.uniform(1881.0, 1999.0, 1000)
    h, n = dem.surfaces(x, y)
    np.testing.assert_allclose(h, 0.25 * x - 0.125 * y + 10.0, rtol=0, atol=2e-4)
    expect = np.array([-0.25, 0.125, 1.0]) / math.sqrt(0.25**2 + 0.125**2 + 1.0)
    np.testing.assert_allclose(n, np.broadcast_to(expect, n.shape), rtol=0, atol=1e-5)


def test_import_raster_window_bbox_and_body(plane_tif, tmp_path):
    # A window of the plane: its samples are GDAL's, its extent the window's.
    out = tmp_path / "window.h5"
    rep = regolith.import_raster(plane_tif, out, grid="w", window=(10, 20, 30, 40), body="Mars")
    assert rep["window"] == (10, 20, 30, 40) and (rep["rows"], rep["cols"]) == (30, 40)
    ds = gdal.Open(str(plane_tif))  # kept alive while its band is read
    expected = ds.GetRasterBand(1).ReadAsArray()[10:40, 20:60]
    with h5py.File(out, "r") as f:
        np.testing.assert_array_equal(f["grids/w/level0"][...], expected)
        assert f["grids/w"].attrs["body"] == b"Mars"  # fixed-length (format 1.4)
    dem = regolith.open(out)
    assert dem.extent == (520.0, 560.0, 1960.0, 1990.0)
    x, y = np.array([520.5, 559.5]), np.array([1989.5, 1960.5])
    np.testing.assert_allclose(dem.heights(x, y), 0.25 * x - 0.125 * y + 10.0, rtol=0,
                               atol=2e-4)
    # A bounding box in degrees (the plane lies near 0 deg N, 0 deg E on Mars).
    deg = 180.0 / (math.pi * 3396190.0)  # degrees per metre
    box = (520.0 * deg, 1960.0 * deg, 560.0 * deg, 1990.0 * deg)
    rep = regolith.import_raster(plane_tif, tmp_path / "bbox.h5", grid="b", bbox=box)
    assert rep["window"] == (10, 20, 30, 40)
    with pytest.raises(regolith.RasterImportError, match="both a window and a bounding box"):
        regolith.import_raster(plane_tif, tmp_path / "x.h5", window=(0, 0, 1, 1), bbox=box)


def test_import_raster_with_the_zfp_codec_reads_the_same_samples(plane_tif, tmp_path):
    a, b = tmp_path / "deflate.h5", tmp_path / "zfp.h5"
    regolith.import_raster(plane_tif, a, grid="plane", patch_size=64, deflate=4)
    regolith.import_raster(plane_tif, b, grid="plane", patch_size=64, compression="zfp")
    x = np.linspace(501.0, 659.0, 777)
    y = np.linspace(1881.0, 1999.0, 777)
    np.testing.assert_array_equal(regolith.open(a).heights(x, y), regolith.open(b).heights(x, y))
    with h5py.File(b, "r") as f:  # HDF5 records the ZFP filter; h5py decodes it
        plist = f["grids/plane/level0"].id.get_create_plist()
        assert plist.get_nfilters() == 1 and plist.get_filter(0)[0] == 32013
        with h5py.File(a, "r") as g:
            np.testing.assert_array_equal(f["grids/plane/level0"][...],
                                          g["grids/plane/level0"][...])
    with pytest.raises(ValueError,
                       match=r"^store::codecNamed\(\): codec 'lz4', expected deflate or zfp$"):
        regolith.import_raster(plane_tif, tmp_path / "x.h5", compression="lz4")
    with pytest.raises(regolith.InvalidArgument, match="with the zfp codec"):
        regolith.import_raster(plane_tif, tmp_path / "x.h5", compression="zfp", deflate=6)
    assert not (tmp_path / "x.h5").exists()


def test_import_raster_of_a_height_map_and_a_sinusoidal_dem(tmp_path):
    # An 8-bit PNG height map placed by keywords: samples GDAL's value x scale + offset.
    values = (np.arange(7 * 9).reshape(7, 9) * 37 % 256).astype(np.uint8)
    mem = gdal.GetDriverByName("MEM").Create("", 9, 7, 1, gdal.GDT_Byte)
    mem.GetRasterBand(1).WriteArray(values)
    png = tmp_path / "h.png"
    gdal.GetDriverByName("PNG").CreateCopy(str(png), mem)
    mem = None
    with pytest.raises(regolith.RasterImportError, match="spacing=, origin=, body="):
        regolith.import_raster(png, tmp_path / "x.h5")
    with pytest.raises(ValueError, match="needs both spacing= and origin="):
        regolith.import_raster(png, tmp_path / "x.h5", spacing=2.0, body="Moon")
    out = tmp_path / "h.h5"
    regolith.import_raster(png, out, spacing=(2.0, 3.0), origin=(10.0, 20.0), body="Moon",
                           height_scale=0.5, height_offset=-7.0, heading=90.0)
    info = regolith.Store(out).grid("h")
    assert info.placement == "local_tangent_plane" and info.crs is None
    assert (info.spacing_x, info.spacing_y, info.body) == (2.0, 3.0, "Moon")
    with h5py.File(out, "r") as f:
        np.testing.assert_array_equal(f["grids/h/level0"][...],
                                      (values * 0.5 - 7.0).astype(np.float32))
    # A sinusoidal DEM goes through PROJ; its CRS is recorded as WKT2.
    from osgeo import osr
    ds = gdal.GetDriverByName("GTiff").Create(str(tmp_path / "s.tif"), 6, 5, 1, gdal.GDT_Float32)
    srs = osr.SpatialReference()
    srs.ImportFromProj4("+proj=sinu +lon_0=137 +R=3396190 +units=m +no_defs")
    ds.SetProjection(srs.ExportToWkt())
    ds.SetGeoTransform([24000.0, 25.0, 0.0, -272000.0, 0.0, -25.0])
    ds.GetRasterBand(1).WriteArray(np.full((5, 6), 3.0, dtype=np.float32))
    ds = None
    regolith.import_raster(tmp_path / "s.tif", tmp_path / "s.h5", body="Mars")
    info = regolith.Store(tmp_path / "s.h5").grid("s")
    assert info.placement == "projected" and info.crs.startswith("PROJCRS[")
    dem = regolith.open(tmp_path / "s.h5")
    p = dem.to_body_fixed(np.array([24012.5]), np.array([-272012.5]), np.array([0.0]))[0]
    # OSR's lon/lat of that pixel centre, on the sphere.
    geo = srs.CloneGeogCS()
    srs.SetAxisMappingStrategy(osr.OAMS_TRADITIONAL_GIS_ORDER)
    geo.SetAxisMappingStrategy(osr.OAMS_TRADITIONAL_GIS_ORDER)
    lon, lat, _ = osr.CoordinateTransformation(srs, geo).TransformPoint(24012.5, -272012.5)
    phi, lam = math.radians(lat), math.radians(lon)
    want = 3396190.0 * np.array([math.cos(phi) * math.cos(lam), math.cos(phi) * math.sin(lam),
                                 math.sin(phi)])
    np.testing.assert_allclose(p, want, rtol=0, atol=1e-6)


def test_import_of_a_non_raster_raises_raster_import_error(tmp_path):
    bad = tmp_path / "not-a-raster.tif"
    bad.write_text("hello")
    with pytest.raises(regolith.RasterImportError, match="not-a-raster.tif") as e:
        regolith.import_raster(bad, tmp_path / "x.h5")
    assert isinstance(e.value, regolith.StoreError)
    assert not (tmp_path / "x.h5").exists()


def test_generate_mars_gives_a_planet_whose_samples_h5py_reads(tmp_path):
    out = tmp_path / "mars.h5"
    info = regolith.generate_mars(out, rows=64, patch_size=32)
    assert info.kind == "planet" and (info.rows, info.cols) == (64, 128)
    planet = regolith.open(out)
    assert isinstance(planet, regolith.Planet)
    samples, attrs = level0(out, "mars")
    r = np.arange(0, 64, 7)
    c = np.arange(0, 128, 13)[: r.size]
    dx, dy = (float(v) for v in attrs["spacing"])
    assert (dx, dy) == (180.0 / 64, 180.0 / 64)
    lat = float(attrs["y0"]) - dy * r
    lon = float(attrs["x0"]) + dx * c
    np.testing.assert_array_equal(planet.heights(lat, lon), samples[r, c].astype(np.float64))
    h, n = planet.surfaces(lat, lon)
    np.testing.assert_allclose(np.linalg.norm(n, axis=-1), 1.0, atol=1e-12)
    with pytest.raises(regolith.InvalidArgument, match="rows"):
        regolith.generate_mars(tmp_path / "bad.h5", rows=1)


def test_generate_victoria_rejects_a_bad_spacing(tmp_path):
    with pytest.raises(regolith.InvalidArgument, match="spacing"):
        regolith.generate_victoria(tmp_path / "v.h5", spacing=-1.0)
    assert not (tmp_path / "v.h5").exists()


def test_a_store_that_cannot_be_written_is_a_store_error_naming_the_folder(tmp_path):
    # The folder of the target is a regular file: core::writeFileAtomically cannot create it.
    blocker = tmp_path / "not-a-folder"
    blocker.write_text("x")
    with pytest.raises(regolith.StoreError) as e:
        regolith.generate_victoria(blocker / "v.h5", size=101)
    assert str(e.value) == f"store::writeStore(): {blocker / 'v.h5'}: {blocker} is not a folder"
    assert isinstance(e.value, OSError)
    assert blocker.read_text() == "x"


# ---- rendering ------------------------------------------------------------------------------


def test_render_returns_an_rgba_image_of_the_terrain(victoria):
    dem = regolith.open(victoria)
    bg = (0.0, 0.0, 1.0, 1.0)
    img = dem.render(position=(0.0, -900.0, 300.0), look_at=(0.0, 0.0, -40.0), width=160,
                     height=120, background=bg)
    assert img.shape == (120, 160, 4) and img.dtype == np.uint8
    blue = (img[..., 0] == 0) & (img[..., 1] == 0) & (img[..., 2] == 255)
    assert not blue[60, 80] and not blue[119, 80]  # the crater, and the ground below it
    assert blue[0, 80]  # the sky above the horizon at 1.2 km
    # Looking up at the sky instead: all background.
    sky = dem.render(position=(0.0, -900.0, 300.0), heading_deg=0.0, pitch_deg=60.0,
                     width=64, height=48, background=bg)
    assert ((sky[..., 2] == 255) & (sky[..., 0] == 0)).all()
    with pytest.raises(regolith.InvalidArgument, match="look_at or heading_deg"):
        dem.render(position=(0.0, 0.0, 100.0))


def test_planet_render_draws_the_disc_whole_with_the_far_field(tmp_path):
    # A 0.2° Mars from 3 radii: the clipmap keeps its levels within 180°, the far field draws
    # the rest, so the whole disc of angular radius asin(1/3) is drawn and nothing beyond it.
    out = tmp_path / "mars.h5"
    regolith.generate_mars(out, rows=900)
    mars = regolith.open(out)
    r = 3396190.0
    bg = (0.0, 0.0, 1.0, 1.0)
    img = mars.render(position=(3.0 * r, 0.0, 0.0), look_at=(0.0, 0.0, 0.0), width=160,
                      height=120, near=1000.0, clipmap_size=63, background=bg)
    sky = (img[..., 0] == 0) & (img[..., 1] == 0) & (img[..., 2] == 255)
    y, x = np.mgrid[0:120, 0:160]
    radius = np.hypot(x + 0.5 - 80.0, y + 0.5 - 60.0)
    disc = 60.0 * np.tan(np.arcsin(1.0 / 3.0)) / np.tan(np.radians(22.5))
    assert not sky[radius < 0.95 * disc].any()
    assert sky[radius > 1.15 * disc].all()
    # The clipmap alone, every level (the coarsest, 0.8° apart, spans about 50° each way):
    # the disc's rim stays empty.
    alone = mars.render(position=(3.0 * r, 0.0, 0.0), look_at=(0.0, 0.0, 0.0), width=160,
                        height=120, near=1000.0, clipmap_size=63, background=bg,
                        far_field=False)
    sky_alone = (alone[..., 0] == 0) & (alone[..., 1] == 0) & (alone[..., 2] == 255)
    assert sky_alone[radius < 0.95 * disc].sum() > 50
    assert sky_alone[radius > 1.15 * disc].all()
    with pytest.raises(TypeError):
        mars.render(position=(3.0 * r, 0.0, 0.0), look_at=(0.0, 0.0, 0.0), far_field="yes")


# ---- the rover traverse ---------------------------------------------------------------------


def test_traverse_contacts_equal_dem_queries(victoria):
    r = regolith.run_traverse(victoria, speed=100.0, record_every=50, cache_bytes=1 << 20)
    rec = r["record"]
    assert r["steps"] == 11386 and r["queries"] == 6 * r["steps"]
    assert rec["wheels"].shape == (len(rec["step"]), 6, 3)
    dem = regolith.open(victoria)
    w = rec["wheels"]
    h, n = dem.surfaces(w[..., 0], w[..., 1])
    np.testing.assert_array_equal(w[..., 2], h)
    np.testing.assert_array_equal(rec["normals"], n)
    assert r["peak_resident_bytes"] <= r["budget_bytes"] == 1 << 20
    assert r["cache"]["loads"] == r["reads"] > 0
    assert r["queries_per_second"] > 0


def test_traverse_callback_sees_each_step_and_can_stop(victoria):
    seen = []

    def cb(state):
        seen.append((state["step"], state["wheels"].copy(), state["chassis"]["pitch"]))
        return state["step"] < 30

    r = regolith.run_traverse(victoria, speed=100.0, callback=cb, callback_every=10)
    assert [s for s, _, _ in seen] == [0, 10, 20, 30] and r["steps"] == 31
    # Step 0 stands at the first waypoint, heading along the first segment: the wheels'
    # mean is (0.2/6) m ahead of the centre (axles at +1.1, 0, −1.0, two wheels each).
    path = regolith.default_victoria_path()
    heading = path[1] - path[0]
    heading /= np.linalg.norm(heading)
    np.testing.assert_allclose(seen[0][1][:, :2].mean(axis=0), path[0] + (0.2 / 6) * heading,
                               rtol=0, atol=1e-9)


def test_traverse_bad_options_raise_clear_errors(victoria):
    with pytest.raises(regolith.InvalidArgument, match=r"^regolith.run_traverse\(\): "
                       r"cache_bytes is 0, expected a cache budget > 0 bytes$"):
        regolith.run_traverse(victoria, cache_bytes=0)
    with pytest.raises(ValueError, match=r"path waypoint 1 is \(nan, 0\)"):
        regolith.run_traverse(victoria, path=np.array([[0.0, 0.0], [np.nan, 0.0]]))
    with pytest.raises(regolith.InvalidArgument, match=r"path waypoint 1 \(700, 0\) puts a wheel"):
        regolith.run_traverse(victoria, path=np.array([[0.0, 0.0], [700.0, 0.0]]))
    with pytest.raises(regolith.InvalidArgument, match=r"\(N, 2\) array"):
        regolith.run_traverse(victoria, path=np.zeros(4))

    def boom(state):
        raise KeyError("from the callback")

    with pytest.raises(KeyError, match="from the callback"):
        regolith.run_traverse(victoria, speed=100.0, callback=boom)


def test_rover_settles_on_a_tilted_plane():
    rover = regolith.Rover()
    heading, pitch, roll = math.radians(40.0), math.radians(9.0), math.radians(-14.0)
    # The chassis frame: yaw, then pitch nose-up about left, then roll (right side down).
    f0 = np.array([math.sin(heading), math.cos(heading), 0.0])
    l0 = np.array([-f0[1], f0[0], 0.0])
    u1 = -math.sin(pitch) * f0 + math.cos(pitch) * np.array([0.0, 0.0, 1.0])
    up = -math.sin(roll) * l0 + math.cos(roll) * u1
    w = rover.wheel_positions(10.0, 20.0, heading)
    assert w.shape == (6, 2)
    np.testing.assert_allclose(np.linalg.norm(w - [10.0, 20.0], axis=1).max(), rover.reach)
    h = 5.0 - (up[0] * (w[:, 0] - 10.0) + up[1] * (w[:, 1] - 20.0)) / up[2]
    c = rover.settle(10.0, 20.0, heading, h)
    assert c["pitch"] == pytest.approx(pitch, abs=1e-12)
    assert c["roll"] == pytest.approx(roll, abs=1e-12)
    assert c["height"] == pytest.approx(5.0, abs=1e-12)
    np.testing.assert_allclose(c["up"], up, atol=1e-12)
    h[3] = np.nan
    with pytest.raises(regolith.DomainError, match="wheel 3 at .* has no terrain under it"):
        rover.settle(10.0, 20.0, heading, h)
    with pytest.raises(regolith.InvalidArgument, match="trackWidth"):
        regolith.Rover(track_width=0.0)


def test_traverse_uses_the_given_rover(victoria):
    narrow = regolith.Rover(track_width=1.0)
    r = regolith.run_traverse(victoria, speed=100.0, max_steps=1, record_every=1, rover=narrow)
    w = r["record"]["wheels"][0]
    assert np.linalg.norm(w[0, :2] - w[1, :2]) == pytest.approx(1.0, abs=1e-12)


# ---- the paper's scene: graph and headless renders ------------------------------------------

MARS_A, MARS_B = 3396190.0, 3376200.0  # IAU Mars ellipsoid (topo::Body::marsEllipsoid)


def geodetic_frame(lat_deg, lon_deg, h, a=MARS_A, b=MARS_B):
    """Body-fixed position and east, north, up axes of a planetodetic point (textbook ECEF)."""
    lat, lon = math.radians(lat_deg), math.radians(lon_deg)
    e2 = 1.0 - (b * b) / (a * a)
    n = a / math.sqrt(1.0 - e2 * math.sin(lat) ** 2)
    p = np.array([(n + h) * math.cos(lat) * math.cos(lon), (n + h) * math.cos(lat) * math.sin(lon),
                  (n * (1.0 - e2) + h) * math.sin(lat)])
    east = np.array([-math.sin(lon), math.cos(lon), 0.0])
    up = np.array([math.cos(lat) * math.cos(lon), math.cos(lat) * math.sin(lon), math.sin(lat)])
    return p, east, np.cross(up, east), up


def as_matrix(pose):
    m = np.eye(4)
    m[:3, :3], m[:3, 3] = pose["rotation"], pose["translation"]
    return m


def test_paper_scene_tree_has_the_papers_nodes():
    s = regolith.paper_scene()
    names = s.names()
    assert names[0] == "sun" and s.parent("sun") is None
    assert set(names) == {"sun", "earth", "mars", "victoria", "rover", "mast_camera",
                          "chase_camera", "orbit_camera"}
    assert [s.parent(n) for n in ("earth", "mars", "victoria", "rover", "mast_camera",
                                  "orbit_camera")] == ["sun", "sun", "mars", "victoria", "rover",
                                                       "mars"]
    assert [s.kind(n) for n in ("mars", "victoria", "rover", "mast_camera")] == [
        "terrain", "terrain", "object", "camera"]
    two = regolith.paper_scene(second_dem=True)
    assert two.parent("second_dem") == "mars" and two.kind("second_dem") == "terrain"
    with pytest.raises(regolith.InvalidArgument, match="phobos"):
        s.relative("mars", "phobos")


def test_victoria_sits_where_planetodetic_geodesy_puts_it():
    s = regolith.paper_scene()
    pose = s.relative("mars", "victoria")
    p, east, north, up = geodetic_frame(-2.05, -5.5, -1400.0)
    np.testing.assert_allclose(pose["translation"], p, rtol=0, atol=1e-6)
    np.testing.assert_allclose(pose["rotation"], np.column_stack([east, north, up]), atol=1e-12)
    # The orbit camera hangs 20 km over the site, looking down (its -z along -up).
    cam = s.relative("mars", "orbit_camera")
    np.testing.assert_allclose(cam["translation"], p + 20e3 * up, rtol=0, atol=1e-6)
    np.testing.assert_allclose(-cam["rotation"][:, 2], -up, atol=1e-9)


def test_relative_poses_compose_along_the_tree_and_invert():
    s = regolith.paper_scene()
    s.place_rover(10.0, 20.0, 3.0, heading_deg=90.0)
    local = s.relative("victoria", "rover")
    np.testing.assert_allclose(local["translation"], [10.0, 20.0, 3.0], atol=1e-12)
    # Heading 90° clockwise from north: the rover's forward (x) is east, its left (y) north.
    np.testing.assert_allclose(local["rotation"][:, 0], [1.0, 0.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(local["rotation"][:, 1], [0.0, 1.0, 0.0], atol=1e-12)
    chain = (as_matrix(s.relative("sun", "mars")) @ as_matrix(s.relative("mars", "victoria"))
             @ as_matrix(local))
    direct = as_matrix(s.relative("sun", "rover"))
    # Heliocentric metres (2.3e11): composed in double, agreement to a few tens of µm.
    np.testing.assert_allclose(direct[:3, 3], chain[:3, 3], rtol=0, atol=1e-4)
    np.testing.assert_allclose(direct[:3, :3], chain[:3, :3], atol=1e-12)
    back = as_matrix(s.relative("rover", "sun"))
    np.testing.assert_allclose(back @ direct, np.eye(4), atol=1e-4)
    # Between two nodes on different branches, through their common ancestor (Mars).
    cam_in_rover = as_matrix(s.relative("rover", "orbit_camera"))
    expect = np.linalg.inv(as_matrix(s.relative("mars", "rover"))) @ as_matrix(
        s.relative("mars", "orbit_camera"))
    np.testing.assert_allclose(cam_in_rover, expect, atol=1e-6)


# Small generated data so each render takes a fraction of a second.
SMALL_SCENE = dict(width=160, height=90, planet_rows=120, dem_size=201, dem_spacing=6.0,
                   clipmap_size=63)


def test_render_scene_draws_the_dem_close_up_and_mars_from_afar():
    near = regolith.render_scene(eye=(0.0, -300.0, 400.0), look_at=(0.0, 0.0, 0.0), **SMALL_SCENE)
    assert near.shape == (90, 160, 4) and near.dtype == np.uint8
    assert (near[..., 3] == 255).all()
    # The DEM is drawn greener than the planet (demo::kDemAlbedo vs kPlanetAlbedo).
    r, g = near[35:55, 70:90, 0].astype(int), near[35:55, 70:90, 1].astype(int)
    assert (g > r).mean() > 0.9
    # 15,000 km up the site's vertical, looking at Mars's centre: a reddish disc in the middle
    # with black space around it.
    far = regolith.render_scene(eye=(0.0, 0.0, 1.5e7), look_at=(0.0, 0.0, -3.39e6), up=(0.0, 1.0, 0.0),
                                **SMALL_SCENE)
    centre = far[40:50, 75:85].astype(int)
    assert (centre[..., 0] > centre[..., 1]).all()
    assert far[0, 0, :3].max() < 30 and far[-1, -1, :3].max() < 30
    # The default up (the site's vertical) is parallel to that view: another up is chosen
    # (issue 16), and the disc is drawn all the same.
    default_up = regolith.render_scene(eye=(0.0, 0.0, 1.5e7), look_at=(0.0, 0.0, -3.39e6),
                                       **SMALL_SCENE)
    centre = default_up[40:50, 75:85].astype(int)
    assert (centre[..., 0] > centre[..., 1]).all()
    assert default_up[0, 0, :3].max() < 30 and default_up[-1, -1, :3].max() < 30


def test_render_scene_draws_the_rover_where_it_is_placed():
    view = dict(eye=(0.0, -415.0, 25.0), look_at=(0.0, -395.0, 5.0), **SMALL_SCENE)
    here = regolith.render_scene(rover=(0.0, -395.0, 0.0), **view).astype(int)
    away = regolith.render_scene(rover=(150.0, -395.0, 0.0), **view).astype(int)
    changed = np.abs(here[..., :3] - away[..., :3]).max(axis=2) > 8
    assert changed.sum() > 50
    rows, cols = np.nonzero(changed)
    # The rover is in the middle of the view when it stands at the look-at point.
    assert abs(rows.mean() - 45) < 20 and abs(cols.mean() - 80) < 20


def test_render_scene_presses_tracks_and_checks_their_shape():
    y = np.arange(-420.0, -396.0, 0.05)
    offsets = np.array([[-1.3, 1.1], [1.3, 1.1], [-1.3, 0.0], [1.3, 0.0], [-1.3, -1.0],
                        [1.3, -1.0]])
    tracks = np.stack([np.stack([offsets[:, 0], yy + offsets[:, 1]], axis=1) for yy in y])
    view = dict(eye=(0.0, -425.0, 12.0), look_at=(0.0, -405.0, 5.0), rover=(0.0, -395.0, 0.0),
                **SMALL_SCENE)
    plain = regolith.render_scene(**view).astype(int)
    tracked = regolith.render_scene(tracks=tracks, **view).astype(int)
    changed = np.abs(plain[..., :3] - tracked[..., :3]).max(axis=2) > 4
    assert changed.sum() > 100
    # Ruts are darker where they are pressed.
    assert tracked[changed, :3].sum() < plain[changed, :3].sum()
    with pytest.raises(regolith.InvalidArgument, match=r"tracks has shape \(10, 4, 2\)"):
        regolith.render_scene(tracks=np.zeros((10, 4, 2)), **view)
    with pytest.raises(regolith.InvalidArgument, match="tracks is a dict, expected a TrackLayer"):
        regolith.render_scene(tracks={"wheels": 1}, **view)
    # A TrackLayer pressed with the same steps draws exactly the same ruts.
    layer = regolith.TrackLayer(texel_metres=0.05)
    for step in tracks:
        layer.step(step, width=0.4, depth=0.03)
    np.testing.assert_array_equal(regolith.render_scene(tracks=layer, **view), tracked)


def test_track_layer_presses_cosine_squared_ruts_where_the_wheels_went():
    layer = regolith.TrackLayer(texel_metres=0.05)
    assert layer.tiles == 0 and layer.texel_metres == 0.05
    for y in np.arange(0.0, 5.0, 0.05):
        layer.step(np.array([[1.0, y, 7.0], [3.0, y, 7.0]]), width=0.4, depth=0.03)
    assert layer.tiles >= 1
    # At texel centres ((k + 1/2)·0.05) bilinear interpolation returns the texel itself:
    # depth·cos²(π·d/width), d the distance from the wheel's path (x = 1 or 3).
    x = np.array([1.025, 1.125, 2.975, 3.175, 1.275, 2.025])
    d = layer.depth_at(x, np.full(6, 2.525))
    dist = np.minimum(np.abs(x - 1.0), np.abs(x - 3.0))
    expect = np.where(dist < 0.2, 0.03 * np.cos(np.pi * dist / 0.4) ** 2, 0.0)
    np.testing.assert_allclose(d, expect, rtol=0, atol=1e-7)
    assert d.shape == (6,) and d[0] > 0.028 and d[4] == 0.0 and d[5] == 0.0
    # Driving over the same ground again keeps the deeper rut: it does not dig deeper.
    layer.step(np.array([[1.0, 2.0], [3.0, 2.0]]))
    layer.step(np.array([[1.0, 3.0], [3.0, 3.0]]))
    np.testing.assert_allclose(layer.depth_at(x, np.full(6, 2.525)), d, rtol=0, atol=0)
    with pytest.raises(regolith.InvalidArgument, match=r"wheels has shape \(3,\)"):
        layer.step(np.zeros(3))
    with pytest.raises(regolith.InvalidArgument, match="wheel width"):
        layer.step(np.zeros((6, 2)), width=0.0)
    with pytest.raises(regolith.InvalidArgument, match=r"depthAt\(\): point \(nan"):
        layer.depth_at([np.nan], [0.0])
    layer.clear()
    assert layer.depth_at([1.025], [2.525])[0] == 0.0


def test_dem_render_draws_a_track_layer_as_darker_ruts(victoria):
    dem = regolith.open(victoria)
    h = float(dem.heights(np.array([0.0]), np.array([-400.0]))[0])
    layer = regolith.TrackLayer()
    for y in np.arange(-430.0, -400.0, 0.05):
        layer.step(np.array([[-1.3, y], [1.3, y]]))
    view = dict(position=(0.0, -440.0, h + 6.0), look_at=(0.0, -415.0, h), width=160, height=90,
                fov_deg=50.0)
    plain = dem.render(**view).astype(int)
    tracked = dem.render(tracks=layer, **view).astype(int)
    changed = np.abs(plain[..., :3] - tracked[..., :3]).max(axis=2) > 4
    assert changed.sum() > 50
    assert tracked[changed, :3].sum() < plain[changed, :3].sum()
    # Both ruts show: changed pixels on either side of the image's vertical centre line.
    cols = np.nonzero(changed)[1]
    assert (cols < 75).sum() > 10 and (cols > 85).sum() > 10


def test_render_flyover_writes_every_frame(tmp_path):
    from PIL import Image

    s = regolith.render_flyover(tmp_path / "fly", frames=3, width=96, height=54,
                                **{k: SMALL_SCENE[k] for k in ("planet_rows", "dem_size",
                                                               "dem_spacing", "clipmap_size")})
    files = [str(f) for f in s["files"]]
    assert [f.rsplit("/", 1)[1] for f in files] == ["frame_0000.png", "frame_0001.png",
                                                    "frame_0002.png", "multiview.png"]
    for f in files[:3]:
        with Image.open(f) as im:
            assert im.size == (96, 54)
    assert s["start_distance"] > 1e6 > 100.0 > s["end_distance"] > 0.0
    assert 0 < s["focus_switch_frame"] <= 2
    assert 0.0 < s["render_seconds"] <= s["seconds"]
    with pytest.raises(regolith.InvalidArgument, match="frames"):
        regolith.render_flyover(tmp_path / "none", frames=1)


def test_render_flyover_takes_the_demos_pole_pass_and_approach(tmp_path):
    small = {k: SMALL_SCENE[k] for k in ("planet_rows", "dem_size", "dem_spacing",
                                         "clipmap_size")}
    # From 16 Mars radii, as `regolith demo`: 5 frames, the first the approach's.
    s = regolith.render_flyover(tmp_path / "fly", frames=5, width=96, height=54,
                                over_pole=True, approach_from=16 * 3396190.0, **small)
    assert s["impostor_frames"] == 1, s
    assert s["far_field_frames"] >= 1, s
    assert s["impostor_frames"] + s["far_field_frames"] + s["covered_frames"] == 5, s
    assert s["start_distance"] > 15 * 3396190.0 - 3396190.0 - 10000.0, s
    # Without them the flight starts 8000 km from the rover and never needs the impostor.
    plain = regolith.render_flyover(tmp_path / "plain", frames=5, width=96, height=54, **small)
    assert plain["impostor_frames"] == 0 and abs(plain["start_distance"] - 8.0e6) < 1.0, plain
    with pytest.raises(regolith.InvalidArgument, match="approachFrom"):
        regolith.render_flyover(tmp_path / "bad", frames=3, approach_from=-1.0)
