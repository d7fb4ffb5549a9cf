#!/usr/bin/python3
"""Runs Google Benchmark programs of two or more builds side by side, alternating, and prints
each benchmark's median real time per build and its ratio to the first build.

These machines are noisy (docs/ci.md): a figure from one run is not comparable with one from
another run, but builds alternated within one run see the same noise. Build the old and the
new binaries into two folders first, e.g.

    git stash && ninja -C build topo_bench && cp build/bench/topo_bench /tmp/old/
    git stash pop && ninja -C build topo_bench && cp build/bench/topo_bench /tmp/new/
    /usr/bin/python3 scripts/bench-ab.py old=/tmp/old new=/tmp/new \\
        --bench 'topo_bench:dem/height(s_batch)?/bilinear' --rounds 5 --cpu 0

Each round runs every --bench program:filter of every build once, builds in the order given.
--cpu pins the benchmarks to one processor (taskset), away from other work pinned elsewhere.
Extra arguments after -- go to every benchmark program (default --benchmark_min_time=0.3).
"""
import argparse
import json
import pathlib
import statistics
import subprocess
import sys


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("builds", nargs="+", metavar="NAME=DIR",
                    help="a name and the folder holding that build's benchmark programs")
    ap.add_argument("--bench", action="append", required=True, metavar="PROGRAM:FILTER",
                    help="a program in each build's folder and its --benchmark_filter")
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--cpu", type=int, default=None, help="pin to this processor (taskset)")
    ap.add_argument("extra", nargs="*", default=[], help=argparse.SUPPRESS)
    args, rest = ap.parse_known_args()
    extra = [a for a in rest if a != "--"] or ["--benchmark_min_time=0.3"]

    builds = []
    for b in args.builds:
        name, sep, folder = b.partition("=")
        if not sep or not name or not folder:
            ap.error(f"build {b!r}: expected NAME=DIR")
        builds.append((name, pathlib.Path(folder)))
    if len(builds) < 2:
        ap.error("expected at least two builds to compare")
    benches = []
    for spec in args.bench:
        program, sep, flt = spec.partition(":")
        if not sep or not program or not flt:
            ap.error(f"--bench {spec!r}: expected PROGRAM:FILTER")
        benches.append((program, flt))
    for name, folder in builds:
        for program, _ in benches:
            if not (folder / program).is_file():
                ap.error(f"build {name}: {folder / program}: no such program")
    if args.rounds < 1:
        ap.error(f"--rounds {args.rounds}: expected at least 1")

    times: dict[str, dict[str, list[float]]] = {}
    units: dict[str, str] = {}
    for rnd in range(1, args.rounds + 1):
        for name, folder in builds:
            for program, flt in benches:
                cmd = [str(folder / program), f"--benchmark_filter={flt}",
                       "--benchmark_format=json", *extra]
                if args.cpu is not None:
                    cmd = ["taskset", "-c", str(args.cpu), *cmd]
                print(f"round {rnd}/{args.rounds}: {name} {program}", file=sys.stderr)
                out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
                rows = json.loads(out)["benchmarks"]
                if not rows:
                    print(f"bench-ab: {program} of build {name}: no benchmark matches "
                          f"{flt!r}", file=sys.stderr)
                    return 1
                for row in rows:
                    if row.get("run_type") == "aggregate":
                        continue
                    times.setdefault(row["name"], {}).setdefault(name, []).append(
                        row["real_time"])
                    units[row["name"]] = row["time_unit"]

    first = builds[0][0]
    header = f"{'benchmark':52s} {'unit':4s}" + "".join(f" {n:>10s}" for n, _ in builds)
    header += "".join(f" {n + '/' + first:>12s}" for n, _ in builds[1:])
    print(header)
    for bench in sorted(times):
        med = {n: statistics.median(times[bench][n]) for n, _ in builds if n in times[bench]}
        line = f"{bench:52s} {units[bench]:4s}" + "".join(
            f" {med.get(n, float('nan')):10.2f}" for n, _ in builds)
        # A benchmark one build lacks (added since) has its times and no ratio.
        base = med.get(first, float("nan"))
        line += "".join(f" {med.get(n, float('nan')) / base:12.3f}" for n, _ in builds[1:])
        print(line)
    print(f"(median of {args.rounds} alternated rounds; real time)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
