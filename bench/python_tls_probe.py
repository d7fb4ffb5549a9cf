#!/usr/bin/env python3
"""Profile target for docs/python.md: 60 batches of 1 M heights along the "path" points of
bench/python_vs_cpp.py, written into one out= array, for `perf record`.

    PYTHONPATH=build/bindings/python/package perf record -o /tmp/perf.data \\
        /usr/bin/python3 bench/python_tls_probe.py out/bench/victoria.h5
    perf report -i /tmp/perf.data --stdio
"""

import os
import sys

import numpy as np

import regolith

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from python_vs_cpp import points  # noqa: E402

dem = regolith.open(sys.argv[1] if len(sys.argv) > 1 else "out/bench/victoria.h5",
                    grid="victoria", cache_bytes=64 << 20)
x, y = points(dem, False)
out = np.empty(x.size)
for _ in range(60):
    dem.heights(x, y, out=out)
