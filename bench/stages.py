# SPDX-License-Identifier: GPL-3.0-or-later
"""Where compute()'s time goes: each stage of one call (best of three by total) for the
benchmark's largest meshes, with the defaults, with orientation 'as_is', and with 'as_is' and
bvh_quality 'high'.
Usage: python3 bench/stages.py [ENGINE [MESH,MESH]]"""
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
import shape_diameter as sd  # noqa: E402
from meshes import benchmark_meshes  # noqa: E402

engine = sys.argv[1] if len(sys.argv) > 1 else "opencl"
names = sys.argv[2].split(",") if len(sys.argv) > 2 else ["armadillo-x16", "bunny00-x16"]
for name, v, f in benchmark_meshes():
    if name not in names:
        continue
    # The defaults, then without orientation, then also with the SAH tree everywhere.
    for orientation, quality in (("auto", "auto"), ("as_is", "auto"), ("as_is", "high")):
        best, wall = None, None
        for _ in range(3):
            t0 = time.perf_counter()
            r = sd.compute(v, f, rays=30, engine=engine, orientation=orientation,
                           bvh_quality=quality)
            took = (time.perf_counter() - t0) * 1e3
            if best is None or took < wall:
                best, wall = r, took
        stages = " ".join(f"{k} {x * 1e3:.1f}" for k, x in best.timings.items())
        print(f"{name} ({len(f):,} faces) {engine} orientation={orientation} "
              f"bvh_quality={quality}: "
              f"wall {wall:.0f} ms | {stages}", flush=True)
