#!/usr/bin/env python3
"""Turns topo_bench's JSON output into the Markdown tables of docs/accuracy-vs-time.md.

    ./build/bench/topo_bench --benchmark_min_time=0.2 --benchmark_repetitions=3 \
        --benchmark_report_aggregates_only=true --benchmark_enable_random_interleaving=true \
        --benchmark_out=topo_bench.json --benchmark_out_format=json
    python3 bench/summarize.py topo_bench.json

Figures are medians over the repetitions of CPU ns per query (the per_query counter);
"cv" is the largest coefficient of variation (stddev / mean) in the table, a noise gauge.
Works with or without aggregates (without, each run is its own median).
"""

import json
import statistics
import sys
from collections import defaultdict

KERNELS = ["nearest", "bilinear", "bicubic"]
POINTS = ["rover", "random"]


def load(path):
    with open(path) as f:
        data = json.load(f)
    samples = defaultdict(list)  # run_name -> per-repetition ns/query
    medians, cvs = {}, {}
    for b in data["benchmarks"]:
        name = b.get("run_name", b["name"])
        ns = b["per_query"] * 1e9
        agg = b.get("aggregate_name")
        if agg == "median":
            medians[name] = ns
        elif agg == "cv":
            cvs[name] = b["per_query"]  # already a ratio
        elif agg is None:
            samples[name].append(ns)
    for name, values in samples.items():
        medians.setdefault(name, statistics.median(values))
        if len(values) > 1 and name not in cvs:
            cvs[name] = statistics.pstdev(values) / statistics.mean(values)
    return data.get("context", {}), medians, cvs


def fmt(v):
    return "–" if v is None else (f"{v:.1f}" if v < 100 else f"{v:.0f}")


def table(title, rows, medians, cvs, prefix):
    print(f"**{title}** (median CPU ns per query)\n")
    cols = [(k, p) for p in POINTS for k in KERNELS]
    print("| query | " + " | ".join(f"{k} {p}" for k, p in cols) + " |")
    print("|---|" + "---:|" * len(cols))
    worst = 0.0
    for label, query in rows:
        cells = []
        for k, p in cols:
            name = f"{prefix}/{query}/{k}/{p}"
            cells.append(fmt(medians.get(name)))
            worst = max(worst, cvs.get(name, 0.0))
        print(f"| {label} | " + " | ".join(cells) + " |")
    print(f"\nlargest cv in this table: {100 * worst:.0f} %\n")


def main():
    if len(sys.argv) != 2:
        sys.exit("usage: summarize.py topo_bench.json")
    context, medians, cvs = load(sys.argv[1])
    print(f"date {context.get('date', '?')}, {context.get('num_cpus', '?')} CPUs at "
          f"{context.get('mhz_per_cpu', '?')} MHz, library build type "
          f"{context.get('library_build_type', '?')}\n")

    table("TopoDem, 2048x2048 floats, 1 m", [
        ("height()", "height"),
        ("heights() batch", "heights_batch"),
        ("surface() Grid", "surface_grid"),
        ("surface() BodyFixed", "surface_bodyfixed"),
        ("surfaces() batch Grid", "surfaces_batch_grid"),
        ("surfaces() batch BodyFixed", "surfaces_batch_bodyfixed"),
    ], medians, cvs, "dem")
    table("TopoPlanet, 1440x720 floats, 0.25 deg global", [
        ("height()", "height"),
        ("heights() batch", "heights_batch"),
    ], medians, cvs, "planet")

    print("**Bilinear heights: the library against the hand-written loop, same points**\n")
    print("| points | hand-written | heights() batch | batch / hand | "
          "heights() batch + status | height() single | single / hand |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    for p in POINTS:
        hand = medians.get(f"dem/handwritten/bilinear/{p}")
        batch = medians.get(f"dem/heights_batch/bilinear/{p}")
        status = medians.get(f"dem/heights_batch_status/bilinear/{p}")
        single = medians.get(f"dem/height/bilinear/{p}")
        ratio = (lambda a: "–" if a is None or not hand else f"{a / hand:.2f}")
        print(f"| {p} | {fmt(hand)} | {fmt(batch)} | {ratio(batch)} | {fmt(status)} | "
              f"{fmt(single)} | {ratio(single)} |")
    print()


if __name__ == "__main__":
    main()
