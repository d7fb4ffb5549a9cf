#!/usr/bin/env python3
"""Plots and index.html of `regolith report` (docs/accuracy-vs-time.md).

    report.py --run DIR/run.json --out DIR [--replot-command "regolith report --from ..."]

run.json is what `regolith report` gathered: the machine, the command, the date and each
benchmark program's JSON output (Google Benchmark's shape). This script draws one PNG per
knob where accuracy costs time, each captioned (in the image and on the page) with the machine
and the command, and writes index.html. Every number on the page is written inside an element
carrying data-json="<JSON pointer into run.json>" (and data-scale when shown in other units),
so scripts/check-report.py can check that each came from this run. Needs numpy and
matplotlib (Debian python3-matplotlib).
"""

import argparse
import html
import json
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib import ticker  # noqa: E402

TIME_SCALE = {"ns": 1e-9, "us": 1e-6, "ms": 1e-3, "s": 1.0}


def esc(text):
    return html.escape(str(text), quote=True)


class Row:
    """One benchmark row of one program's output, with its JSON pointer in run.json."""

    def __init__(self, run_index, row_index, data):
        self.ptr = f"/runs/{run_index}/output/benchmarks/{row_index}"
        self.data = data
        self.name = data.get("run_name", data["name"])

    def get(self, key):
        return self.data.get(key)

    def seconds(self, key="real_time"):
        """A time field in seconds (Google Benchmark's real_time/cpu_time in time_unit)."""
        return self.data[key] * TIME_SCALE[self.data.get("time_unit", "ns")]

    def to_unit(self, key, unit):
        """(value in `unit`, scale from the JSON value) for a time field."""
        scale = TIME_SCALE[self.data.get("time_unit", "ns")] / TIME_SCALE[unit]
        return self.data[key] * scale, scale


class Run:
    def __init__(self, doc):
        self.doc = doc
        self.programs = {}
        for i, run in enumerate(doc.get("runs", [])):
            rows = []
            benchmarks = run.get("output", {}).get("benchmarks", [])
            has_median = any(b.get("aggregate_name") == "median" for b in benchmarks)
            for j, b in enumerate(benchmarks):
                if b.get("error_occurred"):
                    continue
                if has_median and b.get("aggregate_name") != "median":
                    continue
                rows.append(Row(i, j, b))
            self.programs[run["program"]] = (i, run, rows)

    def rows(self, program, prefix=""):
        if program not in self.programs:
            return []
        return [r for r in self.programs[program][2] if r.name.startswith(prefix)]

    def run_ptr(self, program):
        return f"/runs/{self.programs[program][0]}"

    def gl_renderer(self):
        for prog in ("clod_bench", "farfield_bench", "effects_bench"):
            if prog in self.programs:
                ctx = self.programs[prog][1].get("output", {}).get("context", {})
                if "gl_renderer" in ctx:
                    return ctx["gl_renderer"], f"{self.run_ptr(prog)}/output/context/gl_renderer"
        return None, None


def value_html(ptr, value, scale=1.0, fmt="{:.3g}"):
    """A number of the page: its text and the JSON pointer it came from."""
    scale_attr = "" if scale == 1.0 else f' data-scale="{scale!r}"'
    return f'<span class="v" data-json="{esc(ptr)}"{scale_attr}>{esc(fmt.format(value * scale))}</span>'


def text_html(ptr, text):
    return f'<span class="s" data-json="{esc(ptr)}">{esc(text)}</span>'


class Page:
    def __init__(self, run, out, replot):
        self.run = run
        self.out = out
        self.replot = replot
        self.sections = []
        m = run.doc["machine"]
        gl, gl_ptr = run.gl_renderer()
        self.caption_text = (
            f"{m['cpu']}, {m['cores']} cores"
            + (f", GL: {gl}" if gl else "")
            + f"; {run.doc['date']}; command: {run.doc['command']}"
            + (f" (re-plotted: {replot})" if replot else "")
        )
        parts = [
            text_html("/machine/cpu", m["cpu"]),
            ", ",
            value_html("/machine/cores", m["cores"], fmt="{:.0f}"),
            " cores",
        ]
        if gl:
            parts += [", GL: ", text_html(gl_ptr, gl)]
        parts += ["; ", text_html("/date", run.doc["date"]), "; command: ",
                  f"<code>{text_html('/command', run.doc['command'])}</code>"]
        if replot:
            parts += [" (re-plotted without running: <code><span data-replot=\"1\">",
                      esc(replot), "</span></code>)"]
        self.caption_html = "".join(parts)

    def figure(self, fig, name, title, program, explanation, table):
        """Saves `fig` as name.png with the caption in the image, and adds its section."""
        cmd = self.run.programs[program][1]["command"]
        readable_log_axes(fig)
        fig.text(0.01, 0.005, "Machine: " + self.caption_text + "\nProgram: " + cmd,
                 fontsize=6.5, va="bottom", ha="left", wrap=True, color="#333333")
        fig.savefig(os.path.join(self.out, name + ".png"), dpi=110)
        plt.close(fig)
        run_ptr = self.run.run_ptr(program)
        caption = (f"{self.caption_html}. Program: <code>"
                   f"{text_html(run_ptr + '/command', cmd)}</code>")
        self.sections.append(
            f'<section id="{esc(name)}"><h2>{esc(title)}</h2><p>{explanation}</p>'
            f'<figure><img src="{esc(name)}.png" alt="{esc(title)}">'
            f"<figcaption>{caption}</figcaption></figure>{table}</section>")

    def missing(self, title, program):
        self.sections.append(
            f"<section><h2>{esc(title)}</h2><p>Not in this run: <code>{esc(program)}</code> "
            "did not run (see <code>--only</code>, or the quick/full mode).</p></section>")

    def write(self):
        doc = self.run.doc
        body = "\n".join(self.sections)
        page = f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>Regolith: accuracy against time</title>
<style>
body {{ font-family: sans-serif; max-width: 1100px; margin: auto; padding: 1em; }}
img {{ max-width: 100%; border: 1px solid #ccc; }}
table {{ border-collapse: collapse; font-size: 90%; margin: 0.5em 0 2em; }}
td, th {{ border: 1px solid #ccc; padding: 2px 6px; text-align: right; }}
td:first-child {{ text-align: left; }}
figcaption, .machine {{ font-size: 85%; color: #444; }}
</style></head><body>
<h1>Regolith: accuracy against time</h1>
<p class="machine">Machine: {self.caption_html}. Mode: {text_html('/mode', doc['mode'])}.
Benchmarks took {value_html('/seconds', doc['seconds'], fmt='{:.0f}')} s. Raw data:
<a href="run.json">run.json</a>. How to run and read this report: docs/accuracy-vs-time.md.</p>
{body}
</body></html>
"""
        path = os.path.join(self.out, "index.html")
        tmp = path + ".tmp"
        with open(tmp, "w", encoding="utf-8") as f:
            f.write(page)
        os.replace(tmp, path)


def table(header, rows):
    """header: column titles (text, no numbers); rows: lists of HTML cells."""
    head = "".join(f"<th>{esc(h)}</th>" for h in header)
    body = "".join("<tr>" + "".join(f"<td>{c}</td>" for c in r) + "</tr>" for r in rows)
    return f"<table><tr>{head}</tr>{body}</table>"


def name_cell(row):
    return text_html(row.ptr + ("/run_name" if "run_name" in row.data else "/name"), row.name)


def readable_log_axes(fig):
    """Plain numbers on log axes ("0.01", "200", "1e-05"), and labelled minor ticks (2, 5)
    on an axis that spans less than two decades, so that no log axis is left with one label."""
    fmt = ticker.FuncFormatter(lambda v, _: f"{v:g}")
    for ax in fig.axes:
        for axis, scale, lim in ((ax.xaxis, ax.get_xscale(), ax.get_xlim()),
                                 (ax.yaxis, ax.get_yscale(), ax.get_ylim())):
            if scale != "log" or lim[0] <= 0 or getattr(axis, "keep_format", False):
                continue
            if math.log10(lim[1] / lim[0]) > 4.0:
                axis.set_major_formatter(ticker.LogFormatterSciNotation())  # 10^-5 ... 10^11
                continue
            axis.set_major_formatter(fmt)
            if math.log10(lim[1] / lim[0]) < 2.0:
                axis.set_minor_locator(ticker.LogLocator(subs=(2.0, 3.0, 5.0)))
                axis.set_minor_formatter(fmt)
                axis.set_tick_params(which="minor", labelsize=7)


def new_fig(ncols=2, width=11.0, height=4.6):
    fig, axes = plt.subplots(1, ncols, figsize=(width, height), squeeze=False)
    fig.subplots_adjust(bottom=0.24, wspace=0.3, left=0.085, right=0.98, top=0.9)
    return fig, axes[0]


KERNEL_STYLE = {"Nearest": ("tab:red", "s"), "Bilinear": ("tab:blue", "o"),
                "Bicubic": ("tab:green", "^")}


# ---- the knobs ------------------------------------------------------------------------------

def kernels(page):
    run = page.run
    rows = run.rows("accuracy_table", "accuracy/")
    title = "Interpolation kernels: error against time per query"
    if not rows:
        return page.missing(title, "accuracy_table")
    fig, (a, b) = new_fig()
    for kernel, (colour, marker) in KERNEL_STYLE.items():
        ks = sorted([r for r in rows if r.get("kernel") == kernel], key=lambda r: -r.get("spacing_m"))
        if not ks:
            continue
        a.plot([r.get("height_ns") for r in ks], [r.get("rms_dh_m") for r in ks], marker=marker,
               color=colour, label=kernel)
        b.plot([r.get("surface_ns") for r in ks], [1e3 * r.get("rms_normal_rad") for r in ks],
               marker=marker, color=colour, label=kernel)
        for r in ks:
            a.annotate(f"{r.get('spacing_m'):g} m", (r.get("height_ns"), r.get("rms_dh_m")),
                       fontsize=7, xytext=(4, 2), textcoords="offset points")
            b.annotate(f"{r.get('spacing_m'):g} m",
                       (r.get("surface_ns"), 1e3 * r.get("rms_normal_rad")), fontsize=7,
                       xytext=(4, 2), textcoords="offset points")
    a.set(xscale="log", yscale="log", xlabel="height() time per query (ns)",
          ylabel="RMS height error (m)", title="Height (labels: grid spacing)")
    b.set(xscale="log", yscale="log", xlabel="surface() time per query (ns)",
          ylabel="RMS normal error (mrad)", title="Normal")
    a.grid(True, which="both", alpha=0.3)
    a.legend(fontsize=8, loc="lower left")
    b.grid(True, which="both", alpha=0.3)
    b.legend(fontsize=8)
    cells = [[name_cell(r), value_html(r.ptr + "/spacing_m", r.get("spacing_m")),
              value_html(r.ptr + "/rms_dh_m", r.get("rms_dh_m")),
              value_html(r.ptr + "/max_dh_m", r.get("max_dh_m")),
              value_html(r.ptr + "/rms_normal_rad", r.get("rms_normal_rad"), 1e3),
              value_html(r.ptr + "/height_ns", r.get("height_ns")),
              value_html(r.ptr + "/surface_ns", r.get("surface_ns"))] for r in rows]
    tab = table(["case", "spacing (m)", "RMS height error (m)", "max height error (m)",
                 "RMS normal error (mrad)", "height() ns/query", "surface() ns/query"], cells)
    page.figure(fig, "kernels", title, "accuracy_table",
                "Each kernel on an analytic surface (three plane waves, exact heights and normals "
                "in closed form) sampled at three grid spacings: RMS error against the time of "
                "one query, both measured in the same run. Lower left is better.", tab)


def kernels_speed(page):
    run = page.run
    rows = run.rows("topo_bench", "dem/")
    title = "Interpolation kernels: time per query on a large DEM"
    if not rows:
        return page.missing(title, "topo_bench")
    fig, (a,) = new_fig(1, 8.0, 2.6 + 0.2 * len(rows))
    groups = {}
    for r in rows:
        parts = r.name.split("/")  # dem/<query>/<kernel>/<points>[_median]
        if len(parts) < 4:
            continue
        groups.setdefault(parts[1], []).append((parts[2], parts[3].split("_")[0], r))
    labels, values, colours = [], [], []
    for query, items in groups.items():
        for kernel, points, r in sorted(items, key=lambda t: (t[1], t[0])):
            labels.append(f"{query} {kernel} {points}")
            values.append(1e9 * r.get("per_query"))
            colours.append(KERNEL_STYLE.get(kernel.capitalize(), ("grey", "o"))[0])
    a.barh(range(len(values)), values, color=colours)
    a.set_yticks(range(len(values)), labels, fontsize=7)
    a.set_xlim(left=1.0)
    a.set(xscale="log", xlabel="CPU time per query (ns, log scale)",
          title="TopoDem queries, rover path (cache-hot) and random points")
    a.grid(True, axis="x", which="both", alpha=0.3)
    fig.subplots_adjust(left=0.3)
    cells = [[name_cell(r), value_html(r.ptr + "/per_query", r.get("per_query"), 1e9)]
             for r in rows]
    page.figure(fig, "kernels_speed", title, "topo_bench",
                "Google Benchmark figures of one query per call on a large float DEM at one "
                "metre spacing (topo_bench, sixteen MiB): the authoritative speeds; the error panel "
                "above times the same kernels on small grids that fit in cache.",
                table(["case", "CPU ns per query"], cells))


def coarse(page):
    run = page.run
    rows = run.rows("store_bench", "store/coarse/")
    title = "Coarse reads: pyramid level against strided reads of level zero"
    if not rows:
        return page.missing(title, "store_bench")
    fig, (a, b) = new_fig()
    names = [r.name.split("/")[2] for r in rows]
    a.bar(names, [r.to_unit("real_time", "ms")[0] for r in rows], color=["tab:blue", "tab:orange"])
    a.set(yscale="log", ylabel="time per 256×256 window (ms, log scale)",
          title="Read time")
    b.bar(names, [r.get("error_m_rms") for r in rows], color=["tab:blue", "tab:orange"],
          label="RMS")
    b.plot(names, [r.get("error_m_max") for r in rows], "kD", label="max")
    b.set(yscale="log", ylabel="error against the 8×8 footprint mean (m, log scale)",
          title="Error of the 1/8-resolution window")
    b.legend(fontsize=8)
    for ax in (a, b):
        ax.grid(True, axis="y", which="both", alpha=0.3)
    cells = [[name_cell(r), value_html(r.ptr + "/real_time", r.get("real_time"),
                                       r.to_unit("real_time", "ms")[1]),
              value_html(r.ptr + "/error_m_rms", r.get("error_m_rms")),
              value_html(r.ptr + "/error_m_max", r.get("error_m_max"))] for r in rows]
    page.figure(fig, "coarse", title, "store_bench",
                "A coarse window (one sample per eight-by-eight block of level zero) read from "
                "pyramid level three, or from level zero through an HDF hyperslab with a stride "
                "of eight. The error is "
                "each coarse sample against the mean of the level-zero samples it stands for, "
                "computed in double (brute force).",
                table(["case", "ms per window", "RMS error (m)", "max error (m)"], cells))


POLICY_COLOURS = {"Lru": "tab:blue", "HitCount": "tab:red", "DecayingHitCount": "tab:green"}
POLICY_LINES = {"Lru": ("-", "o"), "HitCount": ("--", "s"), "DecayingHitCount": (":", "^")}


def cache(page):
    run = page.run
    rows = run.rows("cache_policies", "cache/raw/")
    title = "Cache policy and budget: hit rate"
    if not rows:
        return page.missing(title, "cache_policies")
    traces = []
    for r in rows:
        if r.get("trace") not in traces:
            traces.append(r.get("trace"))
    ncols = 3
    nrows = (len(traces) + ncols - 1) // ncols
    fig, axes = plt.subplots(nrows, ncols, figsize=(11.0, 3.0 * nrows + 1.0), squeeze=False)
    fig.subplots_adjust(bottom=0.17, hspace=0.5, wspace=0.3, left=0.07, right=0.98, top=0.92)
    for k, trace in enumerate(traces):
        ax = axes[k // ncols][k % ncols]
        tr = [r for r in rows if r.get("trace") == trace]
        for policy, colour in POLICY_COLOURS.items():
            pr = sorted([r for r in tr if r.get("policy") == policy],
                        key=lambda r: r.get("capacity_MiB"))
            if pr:
                ax.plot([r.get("capacity_MiB") for r in pr],
                        [100.0 * r.get("loads") / r.get("requests") for r in pr],
                        linestyle=POLICY_LINES[policy][0], marker=POLICY_LINES[policy][1],
                        color=colour, label=policy)
        best = {}
        for r in tr:
            best[r.get("capacity_MiB")] = 100.0 * r.get("belady_loads") / r.get("requests")
        caps = sorted(best)
        ax.plot(caps, [best[c] for c in caps], "k-", lw=0.8, label="Belady (optimum)")
        ax.set(xscale="log", yscale="log", title=trace, xlabel="cache budget (MiB)",
               ylabel="miss rate (% of requests)")
        ax.grid(True, which="both", alpha=0.3)
        if k == 0:
            ax.legend(fontsize=7)
    for k in range(len(traces), nrows * ncols):
        axes[k // ncols][k % ncols].axis("off")
    cells = [[name_cell(r), value_html(r.ptr + "/capacity_MiB", r.get("capacity_MiB")),
              value_html(r.ptr + "/hit_rate", r.get("hit_rate"), 100.0, "{:.4g}"),
              value_html(r.ptr + "/loads", r.get("loads"), fmt="{:.0f}"),
              value_html(r.ptr + "/belady_loads", r.get("belady_loads"), fmt="{:.0f}"),
              value_html(r.ptr + "/ns_per_request", r.get("ns_per_request"))] for r in rows]
    page.figure(fig, "cache_hit", title, "cache_policies",
                "PatchCache eviction policies replayed on rover traces (every request reaches the "
                "cache): misses (patch loads) against the budget, with Belady's offline optimum as "
                "the floor no policy can beat.",
                table(["case", "budget (MiB)", "hit rate (%)", "loads", "Belady loads",
                       "ns per request"], cells))


def cache_speed(page):
    run = page.run
    rows = run.rows("cache_policies", "cache/raw/")
    trav = [r for r in run.rows("store_bench", "store/rover/paged_heights")
            if r.get("budget_MiB") is not None]
    # The survey traverse (comes back over its patches) against the budget; older runs have
    # only the one-way path's two budgets.
    survey = [r for r in run.rows("store_bench", "store/rover/survey/")
              if r.get("budget_patches") is not None]
    title = "Cache policy and budget: time"
    if not rows and not trav and not survey:
        return page.missing(title, "cache_policies and store_bench")
    fig, (a, b) = new_fig()
    program = "cache_policies" if rows else "store_bench"
    trace = "loop+window" if any(r.get("trace") == "loop+window" for r in rows) else (
        rows[0].get("trace") if rows else None)
    for policy, colour in POLICY_COLOURS.items():
        pr = sorted([r for r in rows if r.get("policy") == policy and r.get("trace") == trace],
                    key=lambda r: r.get("capacity_MiB"))
        if pr:
            a.plot([r.get("capacity_MiB") for r in pr], [r.get("ns_per_request") for r in pr],
                   marker="o", color=colour, label=policy)
    a.set_ylim(bottom=0)
    a.set(xscale="log", xlabel="cache budget (MiB)", ylabel="cache time per request (ns)",
          title=f"Cache's own cost, trace {trace}")
    a.grid(True, which="both", alpha=0.3)
    a.legend(fontsize=8)
    cells = []
    if survey:
        pts = sorted(survey, key=lambda r: r.get("budget_patches"))
        xs = [r.get("budget_patches") for r in pts]
        b.plot(xs, [r.get("items_per_second") / 1e6 for r in pts], "o-", color="tab:purple")
        for r in pts:
            b.annotate(f"{r.get('patch_loads'):.0f}", (r.get("budget_patches"),
                                                       r.get("items_per_second") / 1e6),
                       fontsize=7, xytext=(0, 8), textcoords="offset points", ha="center")
            cells.append([name_cell(r),
                          value_html(r.ptr + "/budget_patches", r.get("budget_patches"),
                                     fmt="{:.0f}"),
                          value_html(r.ptr + "/budget_MiB", r.get("budget_MiB")),
                          value_html(r.ptr + "/items_per_second", r.get("items_per_second"), 1e-6),
                          value_html(r.ptr + "/patch_loads", r.get("patch_loads"), fmt="{:.0f}"),
                          value_html(r.ptr + "/unique_patches", r.get("unique_patches"),
                                     fmt="{:.0f}")])
        b.set_ylim(bottom=0, top=1.25 * max(r.get("items_per_second") / 1e6 for r in pts))
        b.set(xscale="log", xlabel="pager cache budget (patches of 256², 0.25 MiB each)",
              ylabel="traverse speed (M wheel queries/s)",
              title="Survey traverse through the pager (LRU);\nlabels: patch loads")
        b.set_xticks(xs, [f"{x:.0f}" for x in xs])
        b.grid(True, which="both", alpha=0.3)
        caption = ("Left: the cache's own time per request for each policy (cache_policies). "
                   "Right: a rover's lawnmower survey over four by four patches of a store of "
                   "sixty-four MiB (stripes thirty-two metres apart, six wheels every half "
                   "metre, one batch per step), paged through caches of one to sixteen "
                   "patches, cold start (store_bench). Once a row of patches fits, each patch "
                   "is loaded once; below that, every stripe loads its patches again.")
        headers = ["case", "budget (patches)", "budget (MiB)", "M wheel queries/s",
                   "patch loads", "patches touched"]
    elif trav:
        pts = []
        for r in trav:
            pts.append((r.get("budget_MiB"), r.get("items_per_second") / 1e6, r.get("patch_loads"),
                        r))
        pts.sort(key=lambda p: p[0])
        b.plot([p[0] for p in pts], [p[1] for p in pts], "o-", color="tab:purple")
        for p in pts:
            b.annotate(f"{p[2]:.0f} patch loads", (p[0], p[1]), fontsize=7, xytext=(0, 8),
                       textcoords="offset points", ha="center")
            r = p[3]
            cells.append([name_cell(r), value_html(r.ptr + "/budget_MiB", r.get("budget_MiB")),
                          value_html(r.ptr + "/items_per_second", r.get("items_per_second"), 1e-6),
                          value_html(r.ptr + "/patch_loads", r.get("patch_loads"), fmt="{:.0f}"),
                          value_html(r.ptr + "/bytes_read_MB", r.get("bytes_read_MB"))])
        b.set_ylim(bottom=0, top=1.2 * max(p[1] for p in pts))
        b.set_xlim(0.5 * pts[0][0], 2.0 * pts[-1][0])
        b.set(xscale="log", xlabel="pager cache budget (MiB; the store is 64 MiB)",
              ylabel="traverse speed (M wheel queries/s)",
              title="Rover traverse through the pager (LRU)")
        b.grid(True, which="both", alpha=0.3)
        caption = ("Left: the cache's own time per request for each policy (cache_policies). "
                   "Right: six wheels at one kilohertz along a one-kilometre path over a store "
                   "of sixty-four MiB paged through the pager with two budgets, cold start "
                   "(store_bench).")
        headers = ["case", "budget (MiB)", "M wheel queries/s", "patch loads", "MB read"]
    else:
        b.axis("off")
        caption = "The cache's own time per request for each policy (cache_policies)."
        headers = ["case"]
    page.figure(fig, "cache_speed", title, program, caption, table(headers, cells))


def clipmap(page):
    run = page.run
    rows = run.rows("clod_bench", "clod/clipmap/")
    mesh = run.rows("clod_bench", "clod/mesh/")
    title = "Clipmap level size: screen-space error against frame time"
    if not rows:
        return page.missing(title, "clod_bench")
    fig, (a, b) = new_fig()
    dems = sorted({r.name.split("/")[2] for r in rows})
    for dem in dems:
        dr = sorted([r for r in rows if r.name.split("/")[2] == dem], key=lambda r: r.get("vertices"))
        xs = [r.to_unit("real_time", "ms")[0] for r in dr]
        a.plot(xs, [r.get("err_px_p99") for r in dr], "o-", label=f"clipmap, {dem}")
        b.plot([r.get("vertices") for r in dr], xs, "o-", label=f"clipmap, {dem}")
        for r, x in zip(dr, xs):
            a.annotate(r.name.split("/")[3], (x, r.get("err_px_p99")), fontsize=7, xytext=(4, 2),
                       textcoords="offset points")
    if mesh:
        xs = [r.to_unit("real_time", "ms")[0] for r in mesh]
        a.plot(xs, [max(r.get("err_px_p99"), 1e-3) for r in mesh], "ks",
               label="uniform mesh of a pyramid level (level zero is the reference: error "
                     "zero, drawn at 0.001 px)")
        b.plot([r.get("vertices") for r in mesh], xs, "ks", label="uniform mesh")
    b.xaxis.set_major_formatter(ticker.EngFormatter(sep=" "))
    b.xaxis.set_minor_formatter(ticker.NullFormatter())
    b.xaxis.keep_format = True
    a.set(xscale="log", yscale="log", xlabel="frame time (ms)",
          ylabel="screen-space error, 99th percentile (px)", title="Error against frame time")
    b.set(xscale="log", yscale="log", xlabel="vertices per frame", ylabel="frame time (ms)",
          title="Frame time against vertices")
    for ax in (a, b):
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    cells = [[name_cell(r), value_html(r.ptr + "/real_time", r.get("real_time"),
                                       r.to_unit("real_time", "ms")[1]),
              value_html(r.ptr + "/vertices", r.get("vertices"), fmt="{:.0f}"),
              value_html(r.ptr + "/err_px_p99", r.get("err_px_p99")),
              value_html(r.ptr + "/err_px_max", r.get("err_px_max"))] for r in rows + mesh]
    page.figure(fig, "clipmap", title, "clod_bench",
                "One clipmap frame (draw and glFinish, headless) against the level size, and the "
                "screen-space error of the drawn surface against the full-resolution mesh.",
                table(["case", "frame (ms)", "vertices", "error p-ninety-nine (px)",
                       "max error (px)"], cells))


def pgm(page):
    run = page.run
    rows = run.rows("farfield_bench", "pgm/")
    title = "Far field: PGM grid size against screen-space error and frame time"
    if not rows:
        return page.missing(title, "farfield_bench")
    fig, (a, b) = new_fig()
    series = {}
    for r in rows:
        _, view, grid, screen = r.name.split("/")[:4]
        series.setdefault((view, screen), []).append((int(grid.split(":")[1]), r))
    for (view, screen), pts in sorted(series.items()):
        pts.sort(key=lambda p: p[0])
        label = f"{view}, {screen}"
        xs = [p[1].to_unit("real_time", "ms")[0] for p in pts]
        a.plot(xs, [p[1].get("error_px_p99") for p in pts], "o-", label=label)
        for (g, _), x, r in zip(pts, xs, [p[1] for p in pts]):
            a.annotate(f"{g}²", (x, r.get("error_px_p99")), fontsize=7, xytext=(4, 2),
                       textcoords="offset points")
        b.plot([p[0] for p in pts], xs, "o-", label=label)
    a.set(xscale="log", yscale="log", xlabel="frame time (ms)",
          ylabel="screen-space error, 99th percentile (px)", title="Error against frame time")
    b.set(xscale="log", yscale="log", xlabel="PGM grid side (points)", ylabel="frame time (ms)",
          title="Frame time against grid size")
    b.set_xticks([256, 512, 1024, 2048], ["256", "512", "1024", "2048"])
    b.xaxis.set_minor_formatter(ticker.NullFormatter())
    b.xaxis.set_minor_locator(ticker.NullLocator())
    b.xaxis.keep_format = True
    for ax in (a, b):
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    cells = [[name_cell(r), value_html(r.ptr + "/real_time", r.get("real_time"),
                                       r.to_unit("real_time", "ms")[1]),
              value_html(r.ptr + "/grid_ms", r.get("grid_ms")),
              value_html(r.ptr + "/error_px_median", r.get("error_px_median")),
              value_html(r.ptr + "/error_px_p99", r.get("error_px_p99"))] for r in rows]
    page.figure(fig, "pgm", title, "farfield_bench",
                "One frame of the projected-grid mesh (draw and glFinish, headless) against its "
                "grid size; the error is each pixel's surface point against the layers' exact "
                "surface in double, in pixels.",
                table(["case", "frame (ms)", "grid pass (ms)", "median error (px)",
                       "error p-ninety-nine (px)"], cells))


PRECISION_STYLE = {"float_absolute": ("tab:red", "float, absolute positions"),
                   "double_absolute": ("tab:blue", "double, absolute positions"),
                   "float_rerooted": ("tab:green", "float, re-rooted at the terrain")}


def precision(page):
    run = page.run
    rows = run.rows("precision_bench", "precision/")
    title = "Float, double and re-rooted positions: error against distance from the origin"
    if not rows:
        return page.missing(title, "precision_bench")
    fig, (a, b) = new_fig()
    floor = 1e-9  # plotted in place of an exact zero on the log axis
    for mode, (colour, label) in PRECISION_STYLE.items():
        mr = sorted([r for r in rows if r.name.split("/")[1] == mode],
                    key=lambda r: r.get("distance_m"))
        if not mr:
            continue
        a.plot([r.get("distance_m") for r in mr], [max(r.get("error_m_max"), floor) for r in mr],
               "o-", color=colour, label=label)
        b.plot([r.get("distance_m") for r in mr], [1e9 * r.get("s_per_vertex") for r in mr],
               "o-", color=colour, label=label)
    for x, name in ((3.4e6, "Mars radius"), (2.3e11, "Mars–Sun")):
        a.axvline(x, color="grey", lw=0.8, ls=":")
        a.text(x, 1e2, name, rotation=90, fontsize=7, va="top", ha="right")
    a.set(xscale="log", yscale="log", xlabel="distance of the terrain from the origin (m)",
          ylabel="eye-space position error, max (m)",
          title="Vertex position error (zero drawn at 1 nm)")
    b.set(xscale="log", yscale="log", xlabel="distance of the terrain from the origin (m)",
          ylabel="CPU time per vertex (ns)", title="Cost per vertex")
    for ax in (a, b):
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    cells = [[name_cell(r), value_html(r.ptr + "/distance_m", r.get("distance_m")),
              value_html(r.ptr + "/error_m_max", r.get("error_m_max")),
              value_html(r.ptr + "/error_m_rms", r.get("error_m_rms")),
              value_html(r.ptr + "/s_per_vertex", r.get("s_per_vertex"), 1e9)] for r in rows]
    page.figure(fig, "precision", title, "precision_bench",
                "Terrain vertices within a hundred metres of a site, seen by a camera a few metres "
                "away, with the site at a growing distance from the scene's origin. The error is "
                "each vertex's eye-space position against the exact one in double.",
                table(["case", "distance (m)", "max error (m)", "RMS error (m)", "ns per vertex"],
                      cells))


def codecs(page):
    run = page.run
    rows = run.rows("store_bench", "store/codec/")
    imp = run.rows("import_bench", "import/")
    title = "Codecs: size against read time"
    if not rows:
        return page.missing(title, "store_bench")
    fig, (a, b) = new_fig()
    for i, r in enumerate(sorted(rows, key=lambda r: r.get("real_time"))):
        x = r.to_unit("real_time", "ms")[0]
        a.plot(x, r.get("MB"), "o", color="tab:blue")
        a.annotate(r.name.split("/")[2], (x, r.get("MB")), fontsize=8, xytext=(5, -12 + 10 * (i % 3)),
                   textcoords="offset points")
    a.set(xlabel="read time of every patch of a 2048² store (ms)", ylabel="file size (MB)",
          title="Store codecs (level zero only)")
    a.set_ylim(bottom=0)
    a.grid(True, alpha=0.3)
    cells = [[name_cell(r), value_html(r.ptr + "/real_time", r.get("real_time"),
                                       r.to_unit("real_time", "ms")[1]),
              value_html(r.ptr + "/MB", r.get("MB")),
              value_html(r.ptr + "/ratio", r.get("ratio")),
              value_html(r.ptr + "/bytes_per_second", r.get("bytes_per_second"), 1e-6)]
             for r in rows]
    if imp:
        for r in imp:
            x = r.seconds("real_time")
            b.plot(x, r.get("MB"), "s", color="tab:orange")
            b.annotate(r.name.split("/")[1], (x, r.get("MB")), fontsize=8, xytext=(4, 3),
                       textcoords="offset points")
            cells.append([name_cell(r), value_html(r.ptr + "/real_time", r.get("real_time"),
                                                   r.to_unit("real_time", "ms")[1]),
                          value_html(r.ptr + "/MB", r.get("MB")), "", ""])
        b.set(xlabel="import time with the full pyramid (s)", ylabel="output size (MB)",
              title="Import of an 8192² raster (full report only)")
        b.set_ylim(bottom=0)
        b.grid(True, alpha=0.3)
    else:
        names = [r.name.split("/")[2] for r in rows]
        b.bar(names, [r.get("bytes_per_second") / 1e6 for r in rows], color="tab:blue")
        b.set(yscale="log", ylabel="decoded MB per second (log scale)",
              title="Read throughput (imports: in the full report)")
        b.grid(True, axis="y", which="both", alpha=0.3)
    page.figure(fig, "codecs", title, "store_bench",
                "The same terrain written with each codec, then every patch read back through "
                "Store::readWindow (page cache warm: this is decoding, not disk).",
                table(["case", "time (ms)", "size (MB)", "compression ratio", "MB/s decoded"],
                      cells))


def effects(page):
    run = page.run
    rows = run.rows("effects_bench", "effects/")
    title = "Each effect's cost"
    if not rows:
        return page.missing(title, "effects_bench")
    fig, (a, b) = new_fig()
    names = [r.name.split("/")[1] for r in rows]
    ys = range(len(rows))
    a.barh(ys, [r.get("effect_ms") for r in rows], color="tab:orange", label="with the effect")
    a.plot([r.get("bare_ms") for r in rows], ys, "k|", markersize=14, label="bare frame")
    a.set_yticks(ys, names)
    a.set(xlabel="frame time (ms)", title="Frame time, alternated with the bare frame")
    a.legend(fontsize=7)
    ratio = [r.get("ratio") for r in rows]
    # The middle half of the pairs' ratios (older runs have no quartiles: no bar).
    q1 = [r.data.get("ratio_q1", r.get("ratio")) for r in rows]
    q3 = [r.data.get("ratio_q3", r.get("ratio")) for r in rows]
    b.barh(ys, ratio, color="tab:purple")
    b.errorbar(ratio, ys, xerr=[[m - lo for m, lo in zip(ratio, q1)],
                                [hi - m for m, hi in zip(ratio, q3)]],
               fmt="none", ecolor="k", capsize=3, lw=0.8)
    b.axvline(1.0, color="k", lw=0.8)
    b.set_yticks(ys, names)
    b.set(xlabel="frame time ratio, effect over bare\n(median of pairs; bars: middle half)",
          title="Relative cost")
    for ax in (a, b):
        ax.grid(True, axis="x", alpha=0.3)
    fig.subplots_adjust(left=0.12, wspace=0.45, bottom=0.2)

    def quartiles(r):
        if "ratio_q1" not in r.data:
            return "(not measured)"
        return (value_html(r.ptr + "/ratio_q1", r.get("ratio_q1")) + " to "
                + value_html(r.ptr + "/ratio_q3", r.get("ratio_q3")))

    cells = [[name_cell(r), value_html(r.ptr + "/bare_ms", r.get("bare_ms")),
              value_html(r.ptr + "/effect_ms", r.get("effect_ms")),
              value_html(r.ptr + "/ratio", r.get("ratio")), quartiles(r)] for r in rows]
    page.figure(fig, "effects", title, "effects_bench",
                "Frames with only one scene-declared effect, paired with frames of the bare "
                "pipeline (the order alternating from pair to pair) so that the machine's drift "
                "hits both; medians, so that a preempted frame does not count; none is the "
                "noise floor.",
                table(["case", "bare frame (ms, median)", "with effect (ms, median)",
                       "ratio (median of pairs)", "middle half of the ratios"], cells))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--run", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--replot-command", default="")
    args = ap.parse_args()
    with open(args.run, encoding="utf-8") as f:
        doc = json.load(f)
    run = Run(doc)
    page = Page(run, args.out, args.replot_command)
    for knob in (kernels, kernels_speed, coarse, cache, cache_speed, clipmap, pgm, precision,
                 codecs, effects):
        knob(page)
    page.write()
    return 0


if __name__ == "__main__":
    sys.exit(main())
