"""regolith-mpi import on 2 ranks against the single-process `regolith import` (docs/scale.md).

The oracle is the ordinary import of the same sources: every level's samples bit for bit, every
chunk's encoded bytes and filter mask (h5py's read_direct_chunk), every attribute of the root,
the grid and its tiles. Then the failures: a bad source tile and a killed rank fail the job with
a non-zero status, name the tile, and leave neither the store nor the parts' folder behind.

Environment: REGOLITH_BIN, REGOLITH_MPI_BIN, MPIEXEC (mpirun); as root, OpenMPI needs
OMPI_ALLOW_RUN_AS_ROOT=1 and OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 (tools/mpi/CMakeLists.txt sets
them).
"""

import os
import subprocess

import h5py
import numpy as np
import pytest
from osgeo import gdal, osr

gdal.UseExceptions()

REGOLITH = os.environ.get("REGOLITH_BIN", "build/tools/regolith")
REGOLITH_MPI = os.environ.get("REGOLITH_MPI_BIN", "build/tools/mpi/regolith-mpi")
MPIEXEC = os.environ.get("MPIEXEC") or "mpirun"


def mpirun(n, args, env=None):
    cmd = [MPIEXEC, "-np", str(n), "--oversubscribe"]
    if os.geteuid() == 0:
        cmd.append("--allow-run-as-root")
    e = dict(os.environ)
    for k, v in (env or {}).items():  # None: unset
        if v is None:
            e.pop(k, None)
        else:
            e[k] = v
    return subprocess.run(cmd + [REGOLITH_MPI] + args, capture_output=True, text=True,
                          timeout=120, env=e)


def regolith(args):
    r = subprocess.run([REGOLITH] + args, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    return r


def terrain(rows, cols, seed):
    """Smooth terrain with full float precision, a nodata hole and a NaN-free rest."""
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:rows, 0:cols].astype(np.float64)
    z = 1500.0 * np.sin(x / 37.0) * np.cos(y / 53.0) + rng.normal(0.0, 3.0, (rows, cols))
    z = z.astype(np.float32)
    z[rows // 3:rows // 3 + 9, cols // 2:cols // 2 + 17] = -32768.0
    return z


def write_tif(path, z, x0=-180.0, y0=60.0, dx=0.01):
    ds = gdal.GetDriverByName("GTiff").Create(str(path), z.shape[1], z.shape[0], 1,
                                              gdal.GDT_Float32)
    ds.SetGeoTransform((x0, dx, 0.0, y0, 0.0, -dx))
    srs = osr.SpatialReference()
    srs.SetFromUserInput("+proj=longlat +R=3396190 +no_defs")
    ds.SetProjection(srs.ExportToWkt())
    band = ds.GetRasterBand(1)
    band.SetNoDataValue(-32768.0)
    band.WriteArray(z)
    ds = None


def tiles_of(big, folder, n, size):
    """n × n tiles of `size` samples cut from `big` with gdal_translate -srcwin."""
    out = []
    for i in range(n):
        for j in range(n):
            t = folder / f"t_{i}_{j}.tif"
            gdal.Translate(str(t), str(big), srcWin=[j * size, i * size, size, size])
            out.append(t)
    return out


def attrs(obj):
    return {k: obj.attrs[k] for k in obj.attrs}


def same_value(a, b):
    a, b = np.asarray(a), np.asarray(b)
    if a.dtype.kind == "f":
        return a.shape == b.shape and np.array_equal(a, b, equal_nan=True)
    return a.shape == b.shape and np.array_equal(a, b)


def assert_same_store(single, multi):
    with h5py.File(single, "r") as f, h5py.File(multi, "r") as g:
        for k, v in attrs(f).items():
            assert same_value(v, g.attrs[k]), f"root attribute {k}"
        assert set(f["grids"]) == set(g["grids"])
        for name in f["grids"]:
            a, b = f["grids"][name], g["grids"][name]
            fa, ga = attrs(a), attrs(b)
            assert set(fa) == set(ga), name
            for k in fa:
                assert same_value(fa[k], ga[k]), f"grid attribute {k}: {fa[k]!r} vs {ga[k]!r}"
            assert set(a) == set(b), f"objects of grid {name}"
            for t in a.get("tiles", {}):
                ta, tb = a["tiles"][t], b["tiles"][t]
                assert attrs(ta).keys() == attrs(tb).keys()
                for k in attrs(ta):
                    assert same_value(ta.attrs[k], tb.attrs[k]), f"tile {t} attribute {k}"
                compare_dataset(ta["level0"], tb["level0"], f"tile {t} level0")
            for k in range(int(fa["levels"])):
                key = f"level{k}"
                if key in a:
                    compare_dataset(a[key], b[key], key)


def compare_dataset(da, db, what):
    assert da.shape == db.shape, what
    # The first part grows into the store (H5Dset_extent): its maximum shape must end as the
    # grid's, as the single-process writer's.
    assert da.maxshape == db.maxshape, f"{what}: maxshape {da.maxshape} vs {db.maxshape}"
    assert da.chunks == db.chunks, what
    assert da.fillvalue.tobytes() == db.fillvalue.tobytes(), what
    assert attrs(da).keys() == attrs(db).keys(), what
    for k in attrs(da):
        assert same_value(da.attrs[k], db.attrs[k]), f"{what} attribute {k}"
    pa, pb = da.id.get_create_plist(), db.id.get_create_plist()
    assert pa.get_nfilters() == pb.get_nfilters(), what
    for i in range(pa.get_nfilters()):
        assert pa.get_filter(i)[:3] == pb.get_filter(i)[:3], what
    # Samples bit for bit (as integers: NaN payloads and -0 included).
    assert np.array_equal(da[...].view(np.uint32), db[...].view(np.uint32)), what
    # Every chunk's encoded bytes.
    cr, cc = da.chunks
    for r in range(0, da.shape[0], cr):
        for c in range(0, da.shape[1], cc):
            ma, ba = da.id.read_direct_chunk((r, c))
            mb, bb = db.id.read_direct_chunk((r, c))
            assert ma == mb and ba == bb, f"{what} chunk ({r}, {c})"


@pytest.fixture(scope="module")
def sources(tmp_path_factory):
    d = tmp_path_factory.mktemp("mpi")
    big = d / "big.tif"
    write_tif(big, terrain(512, 512, 7))
    odd = d / "odd.tif"
    write_tif(odd, terrain(500, 610, 11))
    tiles = tiles_of(big, d, 4, 128)
    return d, big, odd, tiles


@pytest.mark.parametrize("codec", [["--deflate", "4"], ["--compression", "zfp"]])
def test_one_raster_is_bit_for_bit_the_single_process_import(sources, codec):
    d, big, odd, _ = sources
    for src in (big, odd):
        single, multi = d / f"single_{src.stem}.h5", d / f"multi_{src.stem}.h5"
        opts = ["--patch", "32"] + codec
        regolith(["import", str(src), "--out", str(single)] + opts)
        r = mpirun(2, ["import", str(src), "--out", str(multi)] + opts)
        assert r.returncode == 0, r.stdout + r.stderr
        assert "parts:          2" in r.stdout, r.stdout  # really split
        assert_same_store(single, multi)
        assert [p.name for p in d.iterdir() if ".parts-" in p.name or ".tmp-" in p.name] == []


def test_one_rank_is_the_single_process_import_and_says_it_had_one_rank(sources):
    d, big, _, _ = sources
    single, multi = d / "single_np1.h5", d / "multi_np1.h5"
    opts = ["--patch", "32", "--deflate", "4"]
    regolith(["import", str(big), "--out", str(single)] + opts)
    r = mpirun(1, ["import", str(big), "--out", str(multi)] + opts)
    assert r.returncode == 0, r.stdout + r.stderr
    # The reason for one part is the one rank (it said "too few rows" before stop 44).
    assert "one part (one rank), on rank 0 alone" in r.stdout, r.stdout
    assert_same_store(single, multi)


def test_a_one_node_job_asks_openmpi_for_shared_memory_unless_a_pml_was_chosen(sources):
    """Every rank on one node: regolith-mpi asks OpenMPI for its ob1 point-to-point layer before
    MPI_Init, so that OpenMPI does not load and probe its cm layer's fabrics (docs/scale.md,
    "Stop 45"). OpenMPI's own verbose output is the oracle of what it loaded. A pml the user
    chose (OMPI_MCA_pml, as `mpirun --mca pml` sets it) is kept, and the store is the same."""
    d, big, _, _ = sources
    opts = ["--patch", "32", "--deflate", "4"]
    verbose = {"OMPI_MCA_pml_base_verbose": "100", "OMPI_MCA_mtl_base_verbose": "100"}
    ours, theirs = d / "pml_ob1.h5", d / "pml_chosen.h5"
    r = mpirun(2, ["import", str(big), "--out", str(ours)] + opts,
               env=dict(verbose, OMPI_MCA_pml=None))
    assert r.returncode == 0, r.stdout + r.stderr
    assert "pml ob1 (every rank on one node)" in r.stdout, r.stdout
    assert "initializing pml component ob1" in r.stderr, r.stderr[-3000:]
    assert "component cm" not in r.stderr and "mtl components" not in r.stderr, r.stderr[-3000:]
    # The user's choice: anything but UCX, so OpenMPI tries cm (and its fabrics) first.
    r = mpirun(2, ["import", str(big), "--out", str(theirs)] + opts,
               env=dict(verbose, OMPI_MCA_pml="^ucx"))
    assert r.returncode == 0, r.stdout + r.stderr
    assert "pml ^ucx, as OMPI_MCA_pml set it" in r.stdout, r.stdout
    assert "component cm" in r.stderr, r.stderr[-3000:]
    assert_same_store(ours, theirs)
    # Started without mpirun (a singleton), OpenMPI chooses as it always does.
    single = d / "pml_singleton.h5"
    e = {k: v for k, v in os.environ.items() if not k.startswith("OMPI_")}
    r = subprocess.run([REGOLITH_MPI, "import", str(big), "--out", str(single)] + opts,
                       capture_output=True, text=True, timeout=120, env=e)
    assert r.returncode == 0, r.stdout + r.stderr
    assert "the MPI library's choice (not started by OpenMPI's mpirun)" in r.stdout, r.stdout
    assert_same_store(ours, single)


def test_tiles_are_bit_for_bit_the_single_process_import(sources):
    d, _, _, tiles = sources
    # The command line's order is not the tiles' row order: the store keeps the given order.
    order = tiles[5:] + tiles[:5]
    single, multi = d / "single_tiles.h5", d / "multi_tiles.h5"
    opts = ["--patch", "64", "--deflate", "6", "--grid", "mosaic"]
    regolith(["import"] + [str(t) for t in order] + ["--out", str(single)] + opts)
    r = mpirun(2, ["import"] + [str(t) for t in order] + ["--out", str(multi)] + opts)
    assert r.returncode == 0, r.stdout + r.stderr
    assert "parts:          2" in r.stdout, r.stdout
    assert_same_store(single, multi)


def test_a_bad_tile_fails_the_job_naming_it(sources, tmp_path):
    _, _, _, tiles = sources
    # A spike in a tile of the second rank's rows, refused by --strict while that rank reads it.
    bad = tmp_path / "spike.tif"
    ds = gdal.Open(str(tiles[13]))
    z = ds.GetRasterBand(1).ReadAsArray()
    z[10, 10] = 5.0e7
    gdal.GetDriverByName("GTiff").CreateCopy(str(bad), ds)
    ds = None
    out = gdal.Open(str(bad), gdal.GA_Update)
    out.GetRasterBand(1).WriteArray(z)
    out = None
    mosaic = [str(t) for t in tiles[:13]] + [str(bad)] + [str(t) for t in tiles[14:]]
    store = tmp_path / "bad.h5"
    r = mpirun(2, ["import"] + mosaic + ["--out", str(store), "--patch", "64", "--strict"])
    assert r.returncode != 0
    assert "rank 1" in r.stderr and str(bad) in r.stderr, r.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["spike.tif"]

    # A file that is no raster at all: refused before any rank writes.
    junk = tmp_path / "junk.tif"
    junk.write_bytes(b"not a GeoTIFF\n" * 10)
    r = mpirun(2, ["import"] + [str(t) for t in tiles[:3]] + [str(junk), "--out", str(store)])
    assert r.returncode != 0
    assert str(junk) in r.stderr, r.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["junk.tif", "spike.tif"]


@pytest.mark.parametrize("rank", ["0", "1"])
def test_a_killed_rank_fails_the_job_and_leaves_nothing(sources, tmp_path, rank):
    # The rank raises SIGKILL with its part written; the other rank's clean-up on mpirun's
    # SIGTERM removes the parts (rank 0's own when rank 0 is the one killed). mpirun sends
    # SIGKILL after its grace (odls_base_sigkill_timeout, 1 s by default): with none the
    # parts stay (shown with 0), and a loaded CI machine may need more than 1 s to start the
    # clean-up's shell and remove them (a suspect for one unexplained failure of this test
    # in a full ctest at stops 39 and 42), so the test gives it 3 s (mpirun then ends 4 s
    # later than with 1 s: it waits twice the grace).
    _, big, _, _ = sources
    store = tmp_path / "killed.h5"
    r = mpirun(2, ["import", str(big), "--out", str(store), "--patch", "64"],
               env={"REGOLITH_MPI_TEST_KILL_RANK": rank,
                    "OMPI_MCA_odls_base_sigkill_timeout": "3"})
    assert r.returncode != 0
    assert list(tmp_path.iterdir()) == [], list(tmp_path.iterdir())


def test_one_raster_is_digested_once_by_the_last_rank_beside_the_join(sources, tmp_path):
    # The parts record no digests; the last rank digests the source while rank 0 joins, and
    # the store's provenance carries the digest the single-process import records (the
    # bit-for-bit tests compare every attribute). Here the digest itself is checked against
    # Python's hashlib, and a failing digest fails the job and leaves nothing behind.
    import hashlib
    import json
    _, big, _, _ = sources
    store = tmp_path / "digested.h5"
    r = mpirun(2, ["import", str(big), "--out", str(store), "--patch", "64"])
    assert r.returncode == 0, r.stdout + r.stderr
    assert "digests:        on rank 1 beside the join" in r.stdout, r.stdout
    with h5py.File(store, "r") as f:
        prov = json.loads(f["grids"]["big"].attrs["provenance"])
    [src] = prov["sources"]
    assert src["sha256"] == hashlib.sha256(big.read_bytes()).hexdigest()
    assert src["bytes"] == big.stat().st_size
    store.unlink()

    # Five ranks, four parts: the fifth rank has no part and digests while the others import.
    single = tmp_path / "single.h5"
    regolith(["import", str(big), "--out", str(single), "--patch", "64"])
    r = mpirun(5, ["import", str(big), "--out", str(store), "--patch", "64"])
    assert r.returncode == 0, r.stdout + r.stderr
    assert "parts:          4" in r.stdout, r.stdout
    assert "digests:        on rank 4 beside the parts" in r.stdout, r.stdout
    assert_same_store(single, store)
    store.unlink()
    single.unlink()

    r = mpirun(2, ["import", str(big), "--out", str(store), "--patch", "64"],
               env={"REGOLITH_MPI_TEST_DIGEST_FAILS": "1"})
    assert r.returncode != 0
    assert f"the digests of {big} on rank 1 failed: test: the digests fail" in r.stderr, r.stderr
    assert list(tmp_path.iterdir()) == [], list(tmp_path.iterdir())


def test_a_global_mosaic_is_imported_whole_and_equal(tmp_path):
    # Geographic tiles 180 degrees high: importTiles() snaps the geometry of the whole mosaic
    # only, so regolith-mpi does not split it (one part, on rank 0) and the store is the same.
    big = tmp_path / "globe.tif"
    write_tif(big, terrain(180, 360, 3), x0=-180.0, y0=90.0, dx=1.0)
    tiles = []
    for i in range(2):
        for j in range(2):
            t = tmp_path / f"g_{i}_{j}.tif"
            gdal.Translate(str(t), str(big), srcWin=[j * 180, i * 90, 180, 90])
            tiles.append(str(t))
    single, multi = tmp_path / "single.h5", tmp_path / "multi.h5"
    regolith(["import"] + tiles + ["--out", str(single), "--patch", "8"])
    r = mpirun(2, ["import"] + tiles + ["--out", str(multi), "--patch", "8"])
    assert r.returncode == 0, r.stdout + r.stderr
    assert "one part (a global mosaic" in r.stdout, r.stdout
    assert_same_store(single, multi)
