"""A full disk and a file size limit during `regolith import` and `regolith generate`
(issue 17, docs/reliability.md "Disk full and read errors").

The store must not fit: into a 1 MiB tmpfs mounted for the test (as root; otherwise the
same limit comes from RLIMIT_FSIZE), and under RLIMIT_FSIZE of 256 KiB with SIGXFSZ
ignored (so write(2) fails with EFBIG instead of the process being killed). Each run must
exit non-zero with an error naming the operation, the store and the cause, and leave no
store and no temporary behind. A previous store at the target stays byte for byte.

Environment: as tests/tools/test_cli.py (REGOLITH_BIN).
"""

import os
import resource
import signal
import subprocess
import sys

import numpy as np
import pytest
from osgeo import gdal, osr

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from test_cli import BIN, NO_LEAK_CHECK  # noqa: E402

gdal.UseExceptions()


@pytest.fixture(scope="module")
def source(tmp_path_factory):
    """A 1024 x 1024 Float32 geographic GeoTIFF, noisy so that deflate cannot shrink it."""
    path = tmp_path_factory.mktemp("src") / "big.tif"
    h = np.random.default_rng(17).normal(0.0, 500.0, (1024, 1024)).astype(np.float32)
    ds = gdal.GetDriverByName("GTiff").Create(str(path), 1024, 1024, 1, gdal.GDT_Float32)
    srs = osr.SpatialReference()
    srs.ImportFromProj4("+proj=longlat +R=3396190 +no_defs")
    ds.SetProjection(srs.ExportToWkt())
    ds.SetGeoTransform([137.0, 0.001, 0.0, -4.0, 0.0, -0.001])
    ds.GetRasterBand(1).WriteArray(h)
    ds = None
    return path


def file_size_limit(limit):
    def apply():
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))
    return apply


def try_mount_tmpfs(folder, size):
    if os.geteuid() != 0:
        return False
    r = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(folder)],
                       stderr=subprocess.DEVNULL)
    return r.returncode == 0


@pytest.fixture(params=["tmpfs", "rlimit"])
def small_folder(request, tmp_path):
    """(folder, preexec_fn, the words the error must contain for the cause)."""
    folder = tmp_path / "small"
    folder.mkdir()
    if request.param == "tmpfs" and try_mount_tmpfs(folder, "1m"):
        yield folder, None, "No space left on device"
        subprocess.run(["umount", str(folder)], check=True)
        return
    limit = 256 * 1024 if request.param == "rlimit" else 1024 * 1024
    yield folder, file_size_limit(limit), "File too large"


COMMANDS = {
    "import": lambda src, out: ["import", src, "-o", out, "--deflate", "0"],
    "generate": lambda src, out: ["generate", "mars-planet", "--size", "512", "--out", out],
}


def run_into(folder, preexec, args):
    return subprocess.run([BIN, *map(str, args)], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          text=True, timeout=300, preexec_fn=preexec,
                          env={**os.environ, **NO_LEAK_CHECK})


@pytest.mark.parametrize("command", sorted(COMMANDS))
@pytest.mark.parametrize("old_store", [False, True])
def test_a_store_that_does_not_fit_fails_clearly_and_leaves_nothing(source, small_folder,
                                                                    command, old_store):
    folder, preexec, cause = small_folder
    out = folder / "out.h5"
    old = b""
    if old_store:
        subprocess.run([BIN, "generate", "victoria", "--size", "33", "--resolution", "8",
                        "--out", out], check=True, stdout=subprocess.DEVNULL)
        old = out.read_bytes()
    p = run_into(folder, preexec, COMMANDS[command](source, out))
    # HDF5 1.10's failed H5Fclose (its flush fails too) leaves a freed file behind a live
    # identifier, and H5_term_library() at exit crashed on it (SIGSEGV); the command skips
    # HDF5's shutdown at exit (store::skipHdf5ShutdownAtExit()), so it exits 1.
    assert p.returncode == 1, (p.returncode, p.stderr)
    assert p.stderr.startswith("regolith: error: "), p.stderr
    assert str(out) in p.stderr, p.stderr
    assert cause in p.stderr, p.stderr
    # One line: HDF5's stack is cut to its outermost entry and its cause, without the
    # driver's date (and its line break), the temporary's name and its byte counts.
    assert p.stderr.count("\n") == 1, p.stderr
    assert ".tmp-" not in p.stderr and "time = " not in p.stderr, p.stderr
    left = sorted(x.name for x in folder.iterdir())
    assert left == (["out.h5"] if old_store else []), left
    if old_store:
        assert out.read_bytes() == old
