#!/usr/bin/python3
"""Composed heights and normals through the regolith Python module: CPU time per point.

Writes the Moon scene of the composition tests with h5py (tests/support/catalogue_fixtures.py:
a 2-degree global grid, a 0.25-degree regional grid with a 60 km feather and a nodata hole,
a tangent-plane DEM) into a temporary folder, reads it as docs/cli.md's `moon.json`
(policy "finest"), and times each call on batches of random points, inside the regional grid
(two datasets there) and anywhere on the body (mostly the global grid alone). Prints a
Markdown table of CPU nanoseconds per point, the best of `--rounds` batches after one warm-up
call (docs/python.md, "Composition: catalogue files").

    PYTHONPATH=build/bindings/python/package /usr/bin/python3 bench/python_compose_speed.py
"""

import argparse
import json
import os
import platform
import sys
import tempfile
import time

import numpy as np

import regolith

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests",
                                "support"))
import catalogue_fixtures as cf  # noqa: E402


def best_ns_per_point(call, n, rounds):
    call()  # warm-up: the cells' lists, the patches
    best = float("inf")
    for _ in range(rounds):
        t0 = time.process_time()
        call()
        best = min(best, time.process_time() - t0)
    return best / n * 1e9


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--points", type=int, default=200_000)
    ap.add_argument("--rounds", type=int, default=3)
    args = ap.parse_args()
    if args.points < 1 or args.rounds < 1:
        ap.error(f"--points {args.points} and --rounds {args.rounds}: expected at least 1 each")
    rng = np.random.default_rng(7)
    n = args.points
    where = {
        "inside the regional grid (2 datasets)": (rng.uniform(0.5, 9.5, n),
                                                   rng.uniform(20.5, 29.5, n)),
        "anywhere (mostly the global grid alone)": (np.degrees(np.arcsin(rng.uniform(-1, 1, n))),
                                                    rng.uniform(-180.0, 180.0, n)),
    }
    with tempfile.TemporaryDirectory(prefix="regolith-compose-speed-") as folder:
        cf.write_moon_scene(folder)
        path = os.path.join(folder, "moon.json")
        with open(path, "w", encoding="utf-8") as f:
            json.dump({"policy": "finest", "datasets": [
                {"store": "global.h5", "grid": "global"},
                {"store": "regional.h5", "grid": "regional", "feather_m": cf.FEATHER_M},
                {"store": "regional.h5", "grid": "site", "name": "site, the DEM"}]}, f)
        surf = regolith.read_catalogue(path).surface()
        out = np.empty(n)
        calls = {
            "`surf.heights(lat, lon, out=out)`": lambda la, lo: surf.heights(la, lo, out=out),
            "`surf.heights(lat, lon, contributors=True)`":
                lambda la, lo: surf.heights(la, lo, contributors=True),
            "`surf.surfaces(lat, lon)`": lambda la, lo: surf.surfaces(la, lo),
        }
        print(f"{n} points a batch, best of {args.rounds} after a warm-up, CPU time; "
              f"{platform.node()}, Python {platform.python_version()}\n")
        print("| call | " + " | ".join(where) + " |")
        print("|---|" + "---:|" * len(where))
        for name, call in calls.items():
            cells = []
            for lat, lon in where.values():
                cells.append(f"{best_ns_per_point(lambda: call(lat, lon), n, args.rounds):.0f} ns")
            print(f"| {name} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
