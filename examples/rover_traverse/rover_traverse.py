#!/usr/bin/env python3
"""The rover traverse through the Python module: a six-wheel rover drives a path across the
Victoria-like DEM placed on Mars at 1 kHz, paged through a cache whose budget is an option.
As it drives, the rover presses its wheels into a track overlay (regolith.TrackLayer) every
few centimetres. Prints query throughput and cache statistics, and optionally saves the wheel
contacts (.npz), a plot of the chassis pitch/roll (needs matplotlib) and a headless render of
the DEM with the tracks.

    PYTHONPATH=build/bindings/python/package /usr/bin/python3 \\
        examples/rover_traverse/rover_traverse.py --cache-mb 4 --tracks out/rover/tracks.npz \\
        --image out/rover/tracks.png
"""

import argparse
import math
import os
import sys

import numpy as np

import regolith


def parse_path(text):
    points = []
    for item in text.split():
        try:
            x, y = (float(v) for v in item.split(","))
        except ValueError:
            sys.exit(f"rover_traverse.py: --path item '{item}' is not 'x,y' (grid metres)")
        points.append((x, y))
    return np.array(points, dtype=np.float64)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--store", default="out/rover/victoria.h5",
                    help="store holding the DEM; generated if absent (default %(default)s)")
    ap.add_argument("--grid", default="victoria")
    ap.add_argument("--cache-mb", type=float, default=16.0, help="cache budget, MiB")
    ap.add_argument("--policy", default="lru", choices=["lru", "hitcount", "decaying"])
    ap.add_argument("--path", help="waypoints 'x,y x,y ...' in grid metres")
    ap.add_argument("--speed", type=float, default=1.0, help="m/s")
    ap.add_argument("--step-ms", type=float, default=1.0)
    ap.add_argument("--max-steps", type=int, default=0)
    ap.add_argument("--size", type=int, default=1201, help="samples per side when generating")
    ap.add_argument("--tracks", help="save every --track-every-th step's contacts to this .npz")
    ap.add_argument("--track-every", type=int, default=10)
    ap.add_argument("--plot", help="save a PNG plot of the track and the chassis attitude")
    ap.add_argument("--track-spacing", type=float, default=0.05,
                    help="metres driven between imprints in the track overlay")
    ap.add_argument("--image", help="render the DEM with the tracks to this PNG (headless)")
    a = ap.parse_args()
    if not a.track_spacing > 0:
        sys.exit(f"rover_traverse.py: --track-spacing is {a.track_spacing}, expected > 0 m")

    if not os.path.exists(a.store):
        print(f"Generating the Victoria-like DEM ({a.size} x {a.size} at 1 m) into {a.store} ...")
        os.makedirs(os.path.dirname(a.store) or ".", exist_ok=True)
        regolith.generate_victoria(a.store, size=a.size, grid=a.grid)

    path = parse_path(a.path) if a.path else regolith.default_victoria_path()
    overlay = regolith.TrackLayer(texel_metres=0.05)
    last = {}

    def press(state):
        # Called every few steps (one imprint per --track-spacing metres driven).
        overlay.step(state["wheels"], width=0.4, depth=0.03)
        last.update(ground=state["ground"], height=state["chassis"]["height"])
        return True

    every = max(1, round(a.track_spacing / (a.speed * a.step_ms / 1000.0)))
    try:
        r = regolith.run_traverse(
            a.store, path=path, grid=a.grid, cache_bytes=int(a.cache_mb * 1048576),
            policy=a.policy, speed=a.speed, step=a.step_ms / 1000.0, max_steps=a.max_steps,
            record_every=a.track_every if (a.tracks or a.plot) else 0,
            callback=press, callback_every=every)
    except regolith.Error as e:
        sys.exit(str(e))

    c = r["cache"]
    sim = r["steps"] * a.step_ms / 1000.0
    mib = 1048576.0
    print(f"Traverse of grid '{a.grid}' in {a.store}")
    print(f"  steps            {r['steps']} ({sim:.3f} s simulated, {r['distance']:.1f} m driven)")
    print(f"  wheel queries    {r['queries']} height+normal, {r['query_seconds']:.3f} s in "
          f"queries: {r['queries_per_second'] / 1e6:.2f} M queries/s")
    print(f"  loop             {r['total_seconds']:.3f} s wall ({sim / r['total_seconds']:.0f}x "
          f"real time)")
    print(f"  cache            {c['hits']} hits, {c['misses']} misses, {c['loads']} patch loads, "
          f"{c['evictions']} evictions")
    print(f"  store reads      {r['reads']} hyperslab reads, {r['bytes_read'] / mib:.2f} MiB read")
    print(f"  resident         {c['resident_bytes'] / mib:.2f} MiB now, "
          f"{r['peak_resident_bytes'] / mib:.2f} MiB peak, budget {r['budget_bytes'] / mib:.2f} MiB")
    print(f"  chassis          max tilt {math.degrees(r['max_tilt']):.2f} deg, "
          f"max contact residual {r['max_residual']:.4f} m")

    imprints = (r["steps"] + every - 1) // every
    print(f"  track overlay    {imprints} imprints of the six wheels (every {every} steps), "
          f"{overlay.tiles} tiles")

    if a.image:
        x, y, heading = last["ground"]
        p = np.array([x, y, last["height"]])
        fwd = np.array([math.sin(heading), math.cos(heading), 0.0])
        up = np.array([0.0, 0.0, 1.0])
        dem = regolith.open(a.store, grid=a.grid, cache_bytes=64 << 20)
        img = dem.render(position=tuple(p + 9.0 * fwd + 3.5 * up),
                         look_at=tuple(p - 12.0 * fwd), fov_deg=50.0, width=960, height=540,
                         tracks=overlay)
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        os.makedirs(os.path.dirname(a.image) or ".", exist_ok=True)
        plt.imsave(a.image, img)
        print(f"  image            {a.image}")

    if a.tracks:
        np.savez_compressed(a.tracks, **r["record"])
        print(f"  tracks           {a.tracks} ({len(r['record']['step'])} steps x 6 wheels)")
    if a.plot:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        rec = r["record"]
        fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(11, 4.5))
        for w in range(6):
            ax0.plot(rec["wheels"][:, w, 0], rec["wheels"][:, w, 1], lw=0.6)
        ax0.set_aspect("equal")
        ax0.set_xlabel("x east (m)")
        ax0.set_ylabel("y north (m)")
        ax0.set_title("wheel tracks (grid frame)")
        ax1.plot(rec["time"], np.degrees(rec["chassis"][:, 1]), label="pitch")
        ax1.plot(rec["time"], np.degrees(rec["chassis"][:, 2]), label="roll")
        ax1.set_xlabel("time (s)")
        ax1.set_ylabel("degrees")
        ax1.legend()
        fig.tight_layout()
        fig.savefig(a.plot, dpi=100)
        print(f"  plot             {a.plot}")


if __name__ == "__main__":
    main()
