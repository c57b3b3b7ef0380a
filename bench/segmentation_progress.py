# SPDX-License-Identifier: GPL-3.0-or-later
"""How quickly a segmentation stops when its progress callback raises, on a large mesh.

    .venv/bin/python bench/segmentation_progress.py            # armadillo, 832k faces
    options: --subdivide N (1-to-4 subdivisions of tests/data/armadillo.off, default 2)
             --mode auto|cgal  --postprocess (CGAL's bilateral filter first: minutes)

The SDF is computed once (cached under build/bench-meshes). A first run records every call of
segment(..., progress=...): their number, the largest gap between two calls (what a cancel
can wait for) and the step it fell in. Then, for stops asked at several fractions, the callback
raises at the first call at or past the fraction, and the table gives how long the exception
took to come out of segment() after the raise.
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np
import shape_diameter as sd
from meshes import CACHE, DATA, read_off, subdivide

from bench import machine_line


class Stop(Exception):
    pass


def mesh_and_values(times: int):
    cached = CACHE / f"armadillo-x{4**times}-sdf.npz"
    if cached.exists():
        z = np.load(cached)
        return z["vertices"], z["triangles"], z["values"]
    vertices, triangles = read_off(DATA / "armadillo.off")
    for _ in range(times):
        vertices, triangles = subdivide(vertices, triangles)
    values = sd.compute(vertices, triangles).values
    CACHE.mkdir(parents=True, exist_ok=True)
    np.savez(cached, vertices=vertices, triangles=triangles, values=values)
    return vertices, triangles, values


def recorded_run(vertices, triangles, values, options):
    calls = []
    start = time.perf_counter()
    seg = sd.segment(
        vertices,
        triangles,
        values,
        progress=lambda f: calls.append((time.perf_counter(), f)),
        **options,
    )
    total = time.perf_counter() - start
    times = np.array([start] + [c[0] for c in calls] + [start + total])
    gaps = np.diff(times)
    worst = int(np.argmax(gaps))
    before = calls[min(worst, len(calls) - 1)][1]
    return seg, total, len(calls), gaps, before


def stopped_run(vertices, triangles, values, options, at):
    raised = []

    def progress(fraction):
        if fraction >= at:
            raised.append((time.perf_counter(), fraction))
            raise Stop()

    start = time.perf_counter()
    try:
        sd.segment(vertices, triangles, values, progress=progress, **options)
    except Stop:
        out = time.perf_counter()
        return raised[0][0] - start, raised[0][1], out - raised[0][0]
    return None


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--subdivide", type=int, default=2)
    parser.add_argument("--mode", default="auto", choices=("auto", "cgal"))
    parser.add_argument("--postprocess", action="store_true")
    args = parser.parse_args()
    vertices, triangles, values = mesh_and_values(args.subdivide)
    options = {"mode": args.mode, "postprocess": args.postprocess}
    print(
        f"{machine_line()}, load average {os.getloadavg()[0]:.1f} at the start; "
        f"{len(triangles):,} faces, mode {args.mode}, postprocess {args.postprocess}"
    )
    seg, total, count, gaps, before = recorded_run(vertices, triangles, values, options)
    print(
        f"\nWhole run: {total:.2f} s, {seg.segment_count} segments, {count} progress calls, "
        f"gaps between calls: median {1000 * np.median(gaps):.0f} ms, largest "
        f"{1000 * gaps.max():.0f} ms (before the call at {before:.3f})\n"
    )
    print("| stop asked at | raised after | at fraction | out of segment() after the raise |")
    print("|---:|---:|---:|---:|")
    for at in (0.01, 0.1, 0.2, 0.5, 0.9, 0.97):
        found = stopped_run(vertices, triangles, values, options, at)
        if found is None:
            print(f"| {at} | - | - | not stopped |")
            continue
        raised, fraction, out = found
        print(f"| {at} | {raised:.2f} s | {fraction:.3f} | {1000 * out:.1f} ms |")


if __name__ == "__main__":
    main()
