# SPDX-License-Identifier: GPL-3.0-or-later
"""The BVH made on the device against the host's, end to end: compute() on one OpenCL
device with the test override opencl_tree=host and =device, alternating in one run, the
fastest of --repeat calls of each by wall time, for each orientation (and for a mesh whose
faces 'auto' must reverse); checks that both give the same values.

    python bench/device_tree.py [ENGINE [MESH,MESH]] [--rays R] [--repeat N] [--rounds N]
        [--vary NAME=A,B]

Prints one row a setting: wall time of each tree, their ratio, and the stages of each.
--vary compares two values of another test override instead, on the device's tree (e.g.
opencl_kernel=bvh_per_ray,bvh_per_point; docs/testing.md lists them)."""

import argparse
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
from meshes import benchmark_meshes  # noqa: E402

STAGES = (
    "prepare",
    "build",
    "build wait",
    "orientation (beside cast)",
    "cast (discarded)",
    "build (device)",
    "upload",
    "cast",
    "download",
)
# (label, orientation, reverse every third face first): the last makes 'auto' reverse faces,
# which on the device-tree path costs a second cast.
SETTINGS = (
    ("auto", "auto", False),
    ("as_is", "as_is", False),
    ("auto, 1/3 reversed", "auto", True),
)


def timed(v, f, setting, args, orientation):
    import shape_diameter as sd
    from shape_diameter import _testing

    with _testing.overrides(**{"opencl_tree": "device", args.name: setting}):
        t0 = time.perf_counter()
        r = sd.compute(v, f, rays=args.rays, engine=args.engine, orientation=orientation)
        return (time.perf_counter() - t0) * 1e3, r


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("engine", nargs="?", default="opencl:0")
    parser.add_argument("meshes", nargs="?", default="armadillo-x16,bunny00-x16")
    parser.add_argument("--rays", type=int, default=30)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument(
        "--all-stages",
        action="store_true",
        help="after each row, every stage and step of the device tree's run",
    )
    parser.add_argument(
        "--vary",
        default="opencl_tree=host,device",
        help="the test override and its two values to compare",
    )
    args = parser.parse_args()
    args.name, values = args.vary.split("=", 1)
    first, second = values.split(",")
    wanted = args.meshes.split(",")
    print(
        f"| mesh | faces | orientation | {first} ms | {second} ms | {first}/{second} | "
        f"{first} stages | {second} stages |"
    )
    print("|---|---:|---|---:|---:|---:|---|---|")
    for name, v, f in benchmark_meshes():
        if name not in wanted:
            continue
        for label, orientation, reverse in SETTINGS:
            faces = f.copy()
            if reverse:
                faces[::3] = faces[::3, ::-1]
            best = {}
            for _ in range(args.rounds):
                for tree in (first, second):
                    for _ in range(args.repeat):
                        wall, r = timed(v, faces, tree, args, orientation)
                        if tree not in best or wall < best[tree][0]:
                            best[tree] = (wall, r)
            host, device = best[first], best[second]
            if not np.array_equal(host[1].raw, device[1].raw):
                raise SystemExit(f"{name}: {args.name}={second} gives other values than {first}")

            def stages(r):
                return " ".join(f"{k} {r.timings[k] * 1e3:.1f}" for k in STAGES if k in r.timings)

            print(
                f"| {name} | {len(f):,} | {label} | {host[0]:.1f} | {device[0]:.1f} | "
                f"{host[0] / device[0]:.2f} | {stages(host[1])} | {stages(device[1])} |",
                flush=True,
            )
            if args.all_stages:
                print(
                    "    "
                    + " ".join(f"{k} {x * 1e3:.1f}" for k, x in device[1].timings.items())
                    + f" | device memory {device[1].device_memory / len(f):.0f} B/face ({first}: "
                    f"{host[1].device_memory / len(f):.0f})"
                )


if __name__ == "__main__":
    main()
