# SPDX-License-Identifier: GPL-3.0-or-later
"""OpenCL cast kernels against the CPU engine on the same machine, in one run, interleaved
round by round so that a shared machine's noise hits every contender alike: cast rays/s (the
best of the rounds) and each kernel's ratio to the CPU engine, with a bitwise check of the
values (fibonacci sampling). For the target "OpenCL on PoCL: at least half our CPU
engine" (docs/performance.md), and for choosing each device's default kernel
(opencl_engine.cpp, cast_kernel_for), e.g. on a GPU: opencl armadillo-x16,bunny00-x16
bvh_per_point,bvh4_per_point,bvh8_per_point,bvh_per_ray.
Usage: python3 bench/opencl_vs_cpu.py [ENGINE [MESH,MESH [KERNEL,KERNEL [ROUNDS]]]]"""

import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
import shape_diameter as sd  # noqa: E402
from meshes import benchmark_meshes  # noqa: E402
from shape_diameter import _testing  # noqa: E402

if any(a in ("-h", "--help") for a in sys.argv[1:]):
    sys.exit(print(__doc__))
engine = sys.argv[1] if len(sys.argv) > 1 else "opencl:0"
names = sys.argv[2] if len(sys.argv) > 2 else "armadillo,bunny00,armadillo-x4,armadillo-x16"
kernels = (sys.argv[3] if len(sys.argv) > 3 else "bvh4_per_point,bvh8_per_point").split(",")
rounds = int(sys.argv[4]) if len(sys.argv) > 4 else 2
RAYS = 30

wanted = names.split(",")
for name, v, f in benchmark_meshes(largest="bunny00-x16" in wanted):  # made and cached once
    if name not in wanted:
        continue
    v = np.ascontiguousarray(v, np.float32)
    f = np.ascontiguousarray(f, np.int32)
    contenders = [("cpu", None)] + [(engine, k) for k in kernels]
    best, values = {}, {}
    for _ in range(rounds):
        for eng, kernel in contenders:
            label = kernel or eng
            with _testing.overrides(opencl_kernel=kernel or "engine"):
                r = sd.compute(v, f, rays=RAYS, engine=eng, orientation="as_is", bvh_quality="high")
            rays_per_s = len(r.raw) * RAYS / r.timings["cast"]
            best[label] = max(best.get(label, 0.0), rays_per_s)
            values[label] = r.raw
    print(f"{name} ({len(f):,} faces):", flush=True)
    for label, rate in best.items():
        same = np.array_equal(values[label], values["cpu"])
        print(
            f"  {label:16s} {rate / 1e6:7.2f} Mrays/s  {rate / best['cpu']:5.2f} of cpu  "
            f"bits equal cpu: {same}",
            flush=True,
        )
