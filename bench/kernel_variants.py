# SPDX-License-Identifier: GPL-3.0-or-later
"""Cast time of several settings of the environment (cast kernels, their tuning) on one
OpenCL device, in one process, alternating setting by setting round after round so that a
machine's drift hits each alike: the fastest 'cast' stage of each (and its end-to-end wall
time), with a bitwise check of every setting's values against the first's.

    python bench/kernel_variants.py ENGINE MESH,MESH VARIANT [VARIANT ...]
        [--rays R,R] [--repeat N] [--rounds N] [--orientation as_is]

A VARIANT is NAME:VAR=VALUE[;VAR=VALUE...], e.g. 'per-ray:SDF_OPENCL_KERNEL=bvh_per_ray'
'fetch:SDF_OPENCL_KERNEL=bvh_fetch'. Meshes are bench/meshes.py's names."""

import argparse
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
from meshes import benchmark_meshes  # noqa: E402


def parse_variant(text):
    name, _, settings = text.partition(":")
    env = dict(item.split("=", 1) for item in settings.split(";") if item)
    return name, env


def run(v, f, env, rays, orientation, engine):
    import shape_diameter as sd

    saved = {k: os.environ.get(k) for k in env}
    os.environ.update(env)
    try:
        t0 = time.perf_counter()
        r = sd.compute(v, f, rays=rays, engine=engine, orientation=orientation)
        return (time.perf_counter() - t0) * 1e3, r
    finally:
        for k, old in saved.items():
            if old is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = old


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("engine")
    parser.add_argument("meshes")
    parser.add_argument("variants", nargs="+")
    parser.add_argument("--rays", default="30")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--orientation", default="as_is")
    args = parser.parse_args()
    variants = [parse_variant(text) for text in args.variants]
    wanted = args.meshes.split(",")
    print(f"| mesh | faces | rays | {' | '.join(name for name, _ in variants)} |")
    print("|---|---:|---:|" + "---:|" * len(variants))
    for name, v, f in benchmark_meshes(largest="bunny00-x16" in wanted):
        if name not in wanted:
            continue
        for rays in (int(x) for x in args.rays.split(",")):
            best = {}
            for _ in range(args.rounds):
                for label, env in variants:
                    for _ in range(args.repeat):
                        wall, r = run(v, f, env, rays, args.orientation, args.engine)
                        cast = r.timings["cast"] * 1e3
                        old = best.get(label)
                        best[label] = (min(cast, old[0]) if old else cast,
                                       min(wall, old[1]) if old else wall, r)
            first = variants[0][0]
            for label, _ in variants[1:]:
                if not np.array_equal(best[label][2].raw, best[first][2].raw):
                    raise SystemExit(f"{name}, {rays} rays: {label} gives other values than "
                                     f"{first}")
            cells = " | ".join(f"{best[label][0]:.2f} ({best[label][1]:.1f})"
                               for label, _ in variants)
            print(f"| {name} | {len(f):,} | {rays} | {cells} |", flush=True)
    print("cells: fastest cast ms (fastest end to end ms); values equal bit for bit across "
          "the row")


if __name__ == "__main__":
    main()
