#!/usr/bin/env python3
"""Checks a `regolith report` (the ctest regolith_report_quick, docs/accuracy-vs-time.md).

    check-report.py --regolith BUILD/tools/regolith --out DIR [--no-run] [--replot DIR2] [ARGS...]

Runs `regolith report --out DIR` (quick mode; ARGS are passed on) unless --no-run, then
checks DIR:
  - every <img src> of index.html is a file in DIR holding a valid, non-empty PNG (signature,
    an IHDR chunk with a non-zero size, CRCs of every chunk, an IEND) of at least 200×100
    pixels, and every PNG in DIR is shown on the page;
  - every number on the page came from this run: each element with data-json="<JSON pointer>"
    shows the value at that pointer of DIR/run.json (times data-scale, to the 3 significant
    digits shown; strings exactly), and the page's remaining text has no digits at all;
  - every program of the run has at least one row, no figure says "not in this run", and the
    run's machine, date and command are those on the page.
With --replot DIR2 it then runs `regolith report --from DIR/run.json --out DIR2`, which must
run nothing, and checks DIR2 the same way (its run.json must equal DIR's).
Prints what it checked; exits 1 with a list of the failures.
"""

import argparse
import html.parser
import json
import math
import os
import re
import struct
import subprocess
import sys
import time
import zlib


def check_png(path):
    """Problems with the PNG at `path` (empty list: valid)."""
    with open(path, "rb") as f:
        data = f.read()
    if len(data) == 0:
        return [f"{path}: empty file"]
    if not data.startswith(b"\x89PNG\r\n\x1a\n"):
        return [f"{path}: not a PNG (bad signature)"]
    pos, chunks, problems = 8, [], []
    width = height = 0
    while pos + 8 <= len(data):
        (length,) = struct.unpack(">I", data[pos:pos + 4])
        kind = data[pos + 4:pos + 8]
        body = data[pos + 8:pos + 8 + length]
        crc_bytes = data[pos + 8 + length:pos + 12 + length]
        if len(body) != length or len(crc_bytes) != 4:
            problems.append(f"{path}: truncated {kind!r} chunk")
            break
        if zlib.crc32(kind + body) != struct.unpack(">I", crc_bytes)[0]:
            problems.append(f"{path}: bad CRC in {kind!r} chunk")
        if kind == b"IHDR":
            width, height = struct.unpack(">II", body[:8])
        chunks.append(kind)
        pos += 12 + length
    if not chunks or chunks[0] != b"IHDR":
        problems.append(f"{path}: no IHDR chunk first")
    if b"IDAT" not in chunks:
        problems.append(f"{path}: no image data (IDAT)")
    if not chunks or chunks[-1] != b"IEND":
        problems.append(f"{path}: no IEND chunk at the end")
    if width < 200 or height < 100:
        problems.append(f"{path}: {width}×{height} pixels, expected at least 200×100")
    return problems


def resolve(doc, pointer):
    """RFC 6901 JSON pointer."""
    node = doc
    for part in pointer.lstrip("/").split("/"):
        part = part.replace("~1", "/").replace("~0", "~")
        if isinstance(node, list):
            node = node[int(part)]
        else:
            node = node[part]
    return node


class PageParser(html.parser.HTMLParser):
    """Collects images, data-json elements with their text, and the text outside them."""

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.images = []
        self.values = []  # (pointer, scale, text)
        self.replot = []  # texts of data-replot elements: the `regolith report --from` command
        self.free_text = []
        self.stack = []  # open tags: (tag, value index or None)
        self.skip = 0  # inside <style>/<title>

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "img":
            self.images.append(a.get("src", ""))
            return
        if tag in ("style", "title"):
            self.skip += 1
        index = None
        if "data-json" in a:
            index = len(self.values)
            self.values.append([a["data-json"], float(a.get("data-scale", "1")), ""])
        elif "data-replot" in a:
            index = -1 - len(self.replot)
            self.replot.append("")
        self.stack.append((tag, index))

    def handle_endtag(self, tag):
        if tag in ("style", "title"):
            self.skip -= 1
        while self.stack:
            t, _ = self.stack.pop()
            if t == tag:
                break

    def handle_data(self, data):
        if self.skip:
            return
        for _, index in reversed(self.stack):
            if index is not None and index < 0:
                self.replot[-1 - index] += data
                return
            if index is not None:
                self.values[index][2] += data
                return
        self.free_text.append(data)


def check_report(out, replot_command=None):
    """Problems of the report in `out`; `replot_command`: the `regolith report --from` command
    that wrote it, which the page must show (None: the page must show no re-plot command)."""
    problems = []
    with open(os.path.join(out, "run.json"), encoding="utf-8") as f:
        doc = json.load(f)
    with open(os.path.join(out, "index.html"), encoding="utf-8") as f:
        page = f.read()
    parser = PageParser()
    parser.feed(page)

    # Plots.
    if not parser.images:
        problems.append("index.html shows no plot")
    for src in parser.images:
        path = os.path.join(out, src)
        if "/" in src or not src.endswith(".png"):
            problems.append(f"index.html: image {src!r} is not a PNG beside index.html")
        elif not os.path.isfile(path):
            problems.append(f"index.html: image {src} does not exist")
        else:
            problems += check_png(path)
    shown = set(parser.images)
    for name in sorted(os.listdir(out)):
        if name.endswith(".png") and name not in shown:
            problems.append(f"{name} is in the folder but not on the page")

    # Numbers.
    numbers = strings = 0
    for pointer, scale, text in parser.values:
        try:
            value = resolve(doc, pointer)
        except (KeyError, IndexError, ValueError):
            problems.append(f"index.html: {pointer} is not in run.json (shown as {text!r})")
            continue
        if isinstance(value, str):
            strings += 1
            if text != value:
                problems.append(f"index.html: {pointer} shows {text!r}, run.json has {value!r}")
            continue
        numbers += 1
        try:
            shown_value = float(text)
        except ValueError:
            problems.append(f"index.html: {pointer} shows {text!r}, not a number")
            continue
        expected = float(value) * scale
        # The page shows 3 or 4 significant digits (half a unit of the 3rd), or an integer.
        integer = re.fullmatch(r"-?\d+", text) is not None
        if not math.isclose(shown_value, expected, rel_tol=5.01e-3, abs_tol=0.5 if integer else 0):
            problems.append(f"index.html: {pointer} shows {text}, run.json gives {expected:.6g}")
    for text in parser.replot:
        if text != replot_command:
            problems.append(f"index.html: re-plot command {text!r}, expected {replot_command!r}")
    if replot_command is not None and not parser.replot:
        problems.append("index.html does not name the re-plot command")
    free = "".join(parser.free_text)
    for m in re.finditer(r"\d", free):
        context = free[max(0, m.start() - 40):m.end() + 40].replace("\n", " ")
        problems.append(f"index.html: a number outside data-json: ...{context}...")
        break

    # Coverage.
    for i, run in enumerate(doc["runs"]):
        if not run.get("output", {}).get("benchmarks"):
            problems.append(f"run.json: /runs/{i} ({run['program']}) has no rows")
        if f'data-json="/runs/{i}/output/benchmarks/' not in page:
            problems.append(f"index.html shows no number of /runs/{i} ({run['program']})")
    if "Not in this run" in page:
        problems.append("index.html has a figure whose program did not run")
    for key in ("/command", "/date", "/machine/cpu"):
        if f'data-json="{key}"' not in page:
            problems.append(f"index.html does not show {key}")
    return problems, numbers, strings, len(parser.images)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--regolith")
    ap.add_argument("--out", required=True)
    ap.add_argument("--no-run", action="store_true")
    ap.add_argument("--replot", help="also re-plot DIR/run.json into this folder and check it")
    args, rest = ap.parse_known_args()
    if not args.no_run:
        if not args.regolith:
            ap.error("--regolith is required unless --no-run")
        if os.path.isdir(args.out):
            for name in os.listdir(args.out):  # a fresh report: no plot of an earlier run
                if name.endswith((".png", ".html", ".json")):
                    os.remove(os.path.join(args.out, name))
        start = time.monotonic()
        subprocess.run([args.regolith, "report", "--out", args.out, *rest], check=True)
        print(f"check-report: regolith report took {time.monotonic() - start:.1f} s")
    problems, numbers, strings, images = check_report(args.out)
    print(f"check-report: {images} plots, {numbers} numbers and {strings} strings checked "
          f"against {os.path.join(args.out, 'run.json')}")
    if args.replot:
        if not args.regolith:
            ap.error("--regolith is required with --replot")
        run_json = os.path.join(args.out, "run.json")
        done = subprocess.run([args.regolith, "report", "--from", run_json, "--out", args.replot],
                              check=True, stderr=subprocess.PIPE, text=True)
        if "[1/" in done.stderr:
            problems.append(f"regolith report --from ran a benchmark: {done.stderr}")
        with open(run_json, encoding="utf-8") as a, \
                open(os.path.join(args.replot, "run.json"), encoding="utf-8") as b:
            if json.load(a) != json.load(b):
                problems.append(f"{args.replot}/run.json differs from {run_json}")
        more, numbers, strings, images = check_report(
            args.replot, f"regolith report --out {args.replot} --from {run_json}")
        problems += more
        print(f"check-report: re-plot: {images} plots, {numbers} numbers and {strings} strings "
              f"checked against {os.path.join(args.replot, 'run.json')}")
    for p in problems:
        print("FAIL:", p)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
