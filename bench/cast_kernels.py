# SPDX-License-Identifier: GPL-3.0-or-later
"""The OpenCL engine's cast kernels on one device, compared in one run: cast time (best of
two) and equality of values with the first, then the default kernel's stages with and without
orientation. For choosing defaults (opencl_engine.cpp, cast_kernel_for); bench.py is the
benchmark. Usage: python3 bench/cast_kernels.py [ENGINE [MESH,MESH]]"""
import itertools
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
import shape_diameter as sd  # noqa: E402
from meshes import benchmark_meshes  # noqa: E402

engine = sys.argv[1] if len(sys.argv) > 1 else "opencl"
names = sys.argv[2].split(",") if len(sys.argv) > 2 else ["armadillo-x16", "bunny00-x16"]
grid = {"SDF_OPENCL_KERNEL": ["bvh_per_point", "bvh4_per_point", "bvh8_per_point",
                              "bvh_per_ray"]}
for name, v, f in benchmark_meshes():
    if name not in names:
        continue
    v = np.ascontiguousarray(v, np.float32)
    f = np.ascontiguousarray(f, np.int32)
    reference = None
    print(f"\n{name}: {len(f):,} faces", flush=True)
    for values in itertools.product(*grid.values()):
        env = dict(zip(grid, values))
        os.environ.update(env)
        best = None
        for _ in range(2):
            r = sd.compute(v, f, rays=30, engine=engine, orientation="as_is")
            if best is None or r.timings["cast"] < best.timings["cast"]:
                best = r
        if reference is None:
            reference = best.raw
        same = np.array_equal(best.raw, reference)
        t = {k: round(x * 1e3, 1) for k, x in best.timings.items()}
        print(" ".join(f"{k[4:] if k.startswith('SDF_') else k}={x}" for k, x in env.items()),
              f"cast {t['cast']:7.1f} ms  build {t['build']:6.1f}  same={same}  {t}", flush=True)
    for key in grid:
        os.environ.pop(key, None)
    for orientation in ("as_is", "auto"):
        t0 = time.perf_counter()
        r = sd.compute(v, f, rays=30, engine=engine, orientation=orientation)
        wall = (time.perf_counter() - t0) * 1e3
        print(f"defaults, orientation={orientation}: wall {wall:.0f} ms",
              {k: round(x * 1e3, 1) for k, x in r.timings.items()}, flush=True)
