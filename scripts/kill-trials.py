#!/usr/bin/python3
"""kill -9 trials (issue 17, docs/reliability.md "Kill trials").

Runs `regolith` operations that write a store and kills each with SIGKILL at a random
moment (uniform over 1.2 times its shortest uninterrupted run, so some finish first). Half of
the trials start with an old store at the target name, half with nothing. After each kill
the target must hold one of:
  nothing     (only when there was nothing before),
  old         the old store, byte for byte,
  new         a complete new store: every dataset and attribute of every grid and level is
              bit-identical (h5py) to the same operation's store written without
              interruption, whose level 0 is itself checked against GDAL's read of the
              source (imports) before the trials;
and the folder may hold nothing else but the documented `<target>.tmp-<pid>-<n>` of the
killed process (core::writeFileAtomically; counted, then removed). Anything else is BAD.

Usage: kill-trials.py --regolith build/tools/regolith [--trials 100] [--work DIR]
                      [--ops import,pyramid,generate] [--size 2048]
Exit status 1 if any trial is BAD.
"""

import argparse
import os
import random
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time

import h5py
import numpy as np
from osgeo import gdal, osr

gdal.UseExceptions()


def write_source(path, size):
    """A Float32 geographic GeoTIFF on Mars: smooth relief plus a few NaN holes."""
    r, c = np.mgrid[0:size, 0:size].astype(np.float64)
    h = 800.0 * np.sin(c / 97.0) * np.cos(r / 131.0) + 0.05 * (r - c) - 2500.0
    h = h.astype(np.float32)
    h[size // 3, size // 5] = np.nan
    h[size // 2:size // 2 + 3, size // 2:size // 2 + 4] = np.nan
    ds = gdal.GetDriverByName("GTiff").Create(str(path), size, size, 1, gdal.GDT_Float32,
                                              ["TILED=YES"])
    srs = osr.SpatialReference()
    srs.ImportFromProj4("+proj=longlat +R=3396190 +no_defs")
    ds.SetProjection(srs.ExportToWkt())
    ds.SetGeoTransform([137.0, 0.001, 0.0, -4.0, 0.0, -0.001])
    ds.GetRasterBand(1).WriteArray(h)
    ds = None


def operations(work, size):
    src = os.path.join(work, "source.tif")
    return {
        "import": ["import", src, "--levels", "1", "--threads", "2", "-o"],
        "pyramid": ["import", src, "--levels", "8", "--threads", "2", "-o"],
        "generate": ["generate", "mars-planet", "--size", str(size // 2), "--threads", "2",
                     "--levels", "6", "--out"],
    }


def same_value(a, b):
    """Attribute equality, NaN equal to NaN (a NaN nodata value)."""
    try:
        return np.array_equal(np.asarray(a), np.asarray(b), equal_nan=True)
    except TypeError:  # strings: no NaN
        return np.array_equal(np.asarray(a), np.asarray(b))


def store_problems(path, ref):
    """Differences between two stores as read by h5py (empty: bit-identical content)."""
    problems = []
    try:
        with h5py.File(path, "r") as f, h5py.File(ref, "r") as g:
            names = []
            g.visit(names.append)
            seen = []
            f.visit(seen.append)
            if sorted(seen) != sorted(names):
                return [f"objects differ: {sorted(set(seen) ^ set(names))}"]
            for name in [""] + names:
                a, b = (f[name] if name else f), (g[name] if name else g)
                if set(a.attrs) != set(b.attrs) or not all(
                        same_value(a.attrs[k], b.attrs[k]) for k in a.attrs):
                    problems.append(f"{name or '/'}: attributes differ")
                if isinstance(b, h5py.Dataset):
                    x, y = a[...], b[...]
                    if x.dtype != y.dtype or x.shape != y.shape or x.tobytes() != y.tobytes():
                        problems.append(f"{name}: samples differ")
    except Exception as e:  # an unreadable file is a problem, not a crash of the script
        problems.append(f"unreadable: {e}")
    return problems


def check_against_source(store, src):
    """Level 0 of an imported store equals GDAL's read of the source, sample for sample."""
    ds = gdal.Open(src)  # kept in a variable: a band outliving its dataset crashes GDAL
    expected = ds.GetRasterBand(1).ReadAsArray().astype(np.float32)
    with h5py.File(store, "r") as f:
        (grid,) = f["grids"].values()
        got = (grid.attrs["offset"] + grid.attrs["scale"] * grid["level0"][...]).astype(
            np.float32)
        if "nodata" in grid.attrs:
            got[grid["level0"][...] == np.float32(grid.attrs["nodata"])] = np.nan
    if not np.array_equal(got, expected, equal_nan=True):
        sys.exit(f"kill-trials: the reference {store} does not match GDAL's read of {src}")


def run_once(regolith, args, target):
    t = time.monotonic()
    subprocess.run([regolith, *args, target], check=True, stdout=subprocess.DEVNULL)
    return time.monotonic() - t


def leftovers(work, target, pid):
    """(documented temporaries of pid, anything else unexpected) in the folder."""
    keep = {"source.tif", "old.h5", "ref-import.h5", "ref-pyramid.h5", "ref-generate.h5",
            os.path.basename(target)}
    temp = re.compile(re.escape(os.path.basename(target)) + r"\.tmp-(\d+)-\d+$")
    documented, unexpected = [], []
    for name in os.listdir(work):
        if name in keep:
            continue
        m = temp.match(name)
        (documented if m and int(m.group(1)) == pid else unexpected).append(name)
    return documented, unexpected


def classify(target, had_old, old_bytes, ref):
    if not os.path.exists(target):
        return "BAD: old store lost" if had_old else "nothing"
    with open(target, "rb") as f:
        if had_old and f.read() == old_bytes:
            return "old"
    problems = store_problems(target, ref)
    return "new" if not problems else "BAD: " + "; ".join(problems[:3])


def trial(regolith, args, work, ref, old, duration, rng):
    target = os.path.join(work, "out.h5")
    had_old = rng.random() < 0.5
    if had_old:
        shutil.copyfile(old, target)
    with open(old, "rb") as f:
        old_bytes = f.read()
    p = subprocess.Popen([regolith, *args, target], stdout=subprocess.DEVNULL,
                         stderr=subprocess.DEVNULL)
    time.sleep(rng.uniform(0.0, 1.2 * duration))
    p.send_signal(signal.SIGKILL)
    rc = p.wait()
    outcome = classify(target, had_old, old_bytes, ref)
    documented, unexpected = leftovers(work, target, p.pid)
    for name in documented + unexpected:
        os.remove(os.path.join(work, name))
    if unexpected:
        outcome = "BAD: unexpected files " + ", ".join(unexpected)
    if os.path.exists(target):
        os.remove(target)
    return outcome, rc == -signal.SIGKILL, len(documented) > 0, had_old


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--regolith", required=True)
    ap.add_argument("--trials", type=int, default=100)
    ap.add_argument("--ops", default="import,pyramid,generate")
    ap.add_argument("--size", type=int, default=2048, help="source raster side in samples")
    ap.add_argument("--seed", type=int, default=17)
    ap.add_argument("--work", help="scratch folder (default: a new temporary one, removed)")
    a = ap.parse_args()
    work = a.work or tempfile.mkdtemp(prefix="regolith-kill-")
    os.makedirs(work, exist_ok=True)
    rng = random.Random(a.seed)
    write_source(os.path.join(work, "source.tif"), a.size)
    old = os.path.join(work, "old.h5")
    run_once(a.regolith, ["generate", "victoria", "--size", "65", "--resolution", "8",
                          "--out"], old)
    ops = operations(work, a.size)
    rows, bad = [], 0
    for op in a.ops.split(","):
        ref = os.path.join(work, f"ref-{op}.h5")
        # The shortest of three uninterrupted runs: the machine is shared, one run may be slow.
        duration = min(run_once(a.regolith, ops[op], ref) for _ in range(3))
        if op != "generate":
            check_against_source(ref, os.path.join(work, "source.tif"))
        counts = {}
        for _ in range(a.trials):
            outcome, killed, temp, had_old = trial(a.regolith, ops[op], work, ref, old,
                                                   duration, rng)
            key = outcome if outcome.startswith("BAD") else (
                f"{outcome} ({'killed' if killed else 'finished first'}"
                f"{', temporary left' if temp else ''})")
            counts[key] = counts.get(key, 0) + 1
            if outcome.startswith("BAD"):
                bad += 1
                print(f"{op}: {outcome} (old store before: {had_old})", file=sys.stderr)
        rows.append((op, duration, counts))
    print(f"kill trials: {a.trials} per operation, source {a.size} x {a.size}, seed {a.seed}")
    for op, _, _ in rows:
        print(f"  {op}: regolith {' '.join(ops[op])} <target>")
    print("| operation | uninterrupted run | outcome | trials |\n|---|---|---|---|")
    for op, duration, counts in rows:
        for key in sorted(counts):
            print(f"| {op} | {duration:.2f} s | {key} | {counts[key]} |")
    if not a.work:
        shutil.rmtree(work)
    print(f"BAD trials: {bad}")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
