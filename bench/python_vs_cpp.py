#!/usr/bin/env python3
"""Python batch queries against the C++ batch API, measured side by side in one run.

Runs bench/python_batch_bench (Google Benchmark, C++) and times the same 1 M-point batches
through the regolith Python module, alternating the two `--rounds` times, and prints a
Markdown table of nanoseconds per point (best round of each) and their ratio. The points are
the same in both (python_batch_bench.cpp computes them with the same IEEE operations); both
page the same store through a 64 MiB cache, warmed before timing.

    PYTHONPATH=build/bindings/python/package /usr/bin/python3 bench/python_vs_cpp.py \\
        --bench build/bench/python_batch_bench --store out/bench/victoria.h5

The store (VictoriaGenerator defaults: 1201 x 1201 at 1 m) is generated if absent.
"""

import argparse
import json
import os
import platform
import subprocess
import time

import numpy as np

import regolith

N = 1_000_000


def points(dem, scattered):
    """The same formulas as makePoints() in python_batch_bench.cpp."""
    w, e, s, n = dem.extent
    w, e, s, n = w + 2.0, e - 2.0, s + 2.0, n - 2.0
    t = np.arange(N, dtype=np.float64)
    if scattered:
        u = np.fmod(t * 0.6180339887498949, 1.0)
        v = np.fmod(t * 0.7548776662466927, 1.0)
    else:
        u = t / float(N)
        v = 0.5 + 0.4 * np.sin(t * 1e-5)
    return w + u * (e - w), s + v * (n - s)


def time_python(dem, pts, repetitions):
    """Mean wall time (s) of one batch call over `repetitions` calls (the statistic Google
    Benchmark reports), per kind, pattern and output mode: "new" allocates the result arrays
    on every call, "out" writes into arrays passed as out= (as the C++ benchmark reuses its
    output vectors)."""
    res = {}
    for pattern, (x, y) in pts.items():
        buffers = {"heights": np.empty(N), "surfaces": (np.empty(N), np.empty((N, 3)))}
        for kind in ("heights", "surfaces"):
            fn = getattr(dem, kind)
            for mode in ("new", "out"):
                kwargs = {"out": buffers[kind]} if mode == "out" else {}
                fn(x, y, **kwargs)  # warm
                t0 = time.perf_counter()
                for _ in range(repetitions):
                    fn(x, y, **kwargs)
                res[(kind, pattern, mode)] = (time.perf_counter() - t0) / repetitions
    return res


def time_cpp(bench, store, min_time):
    res = subprocess.run(
        [bench, f"--store={store}", "--benchmark_format=json",
         f"--benchmark_min_time={min_time}"],
        check=True, capture_output=True, text=True)
    out = {}
    for b in json.loads(res.stdout)["benchmarks"]:
        # "BM_Heights/scattered:1" -> ("heights", "scattered")
        name, arg = b["name"].split("/")
        kind = "heights" if name == "BM_Heights" else "surfaces"
        pattern = "scattered" if arg.endswith(":1") else "path"
        assert b["time_unit"] == "ms"
        out[(kind, pattern)] = b["real_time"] * 1e-3  # s per batch
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--bench", default="build/bench/python_batch_bench")
    ap.add_argument("--store", default="out/bench/victoria.h5")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--repetitions", type=int, default=10, help="Python calls per round")
    ap.add_argument("--min-time", default="0.5", help="Google Benchmark min time per round, s")
    a = ap.parse_args()

    if not os.path.exists(a.store):
        os.makedirs(os.path.dirname(a.store) or ".", exist_ok=True)
        regolith.generate_victoria(a.store)
    dem = regolith.open(a.store, grid="victoria", cache_bytes=64 << 20)
    pts = {"scattered": points(dem, True), "path": points(dem, False)}

    best_py, best_cpp = {}, {}
    for _ in range(a.rounds):
        for k, v in time_cpp(a.bench, a.store, a.min_time).items():
            best_cpp[k] = min(best_cpp.get(k, float("inf")), v)
        for k, v in time_python(dem, pts, a.repetitions).items():
            best_py[k] = min(best_py.get(k, float("inf")), v)

    print(f"Machine: {platform.node()}, {os.cpu_count()} CPUs, {platform.processor() or platform.machine()}; "
          f"Python {platform.python_version()}, numpy {np.__version__}")
    print(f"1,000,000 points per batch, best of {a.rounds} alternating rounds of the mean "
          f"time per batch (C++: Google Benchmark, min time {a.min_time} s; Python: "
          f"{a.repetitions} calls)\n")
    print("| query | points | C++ ns/point | Python, new arrays | ratio | Python, out= | ratio |")
    print("|---|---|---:|---:|---:|---:|---:|")
    worst = {"new": 0.0, "out": 0.0}
    for kind in ("heights", "surfaces"):
        for pattern in ("scattered", "path"):
            c = best_cpp[(kind, pattern)] * 1e9 / N
            p = {m: best_py[(kind, pattern, m)] * 1e9 / N for m in ("new", "out")}
            for m in p:
                worst[m] = max(worst[m], p[m] / c)
            print(f"| {kind} | {pattern} | {c:.1f} | {p['new']:.1f} | {p['new'] / c:.2f} "
                  f"| {p['out']:.1f} | {p['out'] / c:.2f} |")
    print(f"\nWorst ratio: {worst['new']:.2f} with new arrays, {worst['out']:.2f} with out= "
          f"(target <= 2)")


if __name__ == "__main__":
    main()
