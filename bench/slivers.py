# SPDX-License-Identifier: GPL-3.0-or-later
"""Slivers lying across the axes, cut into pieces for the BVH (native/accel/bvh_split.h), against
the same build without cutting (the no_sliver_cutting test override), in one run, alternating:
CAD-like fans and needles, and real meshes, whose few slivers must cost nothing.

    .venv/bin/python bench/slivers.py [--rounds 3] [--engine cpu] [--bvh-quality auto]

(On a GPU, --bvh-quality high: the tree a GPU makes for itself is not cut.)

Prints a table: mesh, faces, BVH references with cutting, cast ms without and with, the
ratio, and whether the values are equal (they must be: cutting changes the tree, not a hit).
"""

import argparse
import os
import sys

import numpy as np
import shape_diameter as sd
from shape_diameter import _testing

sys.path.insert(0, os.path.dirname(__file__))
from meshes import DATA, read_off  # noqa: E402


def cylinder(sections):
    """A closed cylinder, radius 1, height 0.2, its caps fanned from their centres."""
    angle = 2 * np.pi * np.arange(sections) / sections
    ring = np.stack([np.cos(angle), np.sin(angle), np.zeros(sections)], 1)
    vertices = np.vstack([ring, ring + [0, 0, 0.2], [[0, 0, 0], [0, 0, 0.2]]])
    k = np.arange(sections)
    nxt = (k + 1) % sections
    bottom, top = 2 * sections, 2 * sections + 1
    faces = np.concatenate(
        [
            np.stack([k, nxt, sections + nxt], 1),
            np.stack([k, sections + nxt, sections + k], 1),
            np.stack([np.full(sections, bottom), nxt, k], 1),
            np.stack([np.full(sections, top), sections + k, sections + nxt], 1),
        ]
    )
    return vertices, faces


def needles(count, seed=0):
    """A box crossed by `count` long, thin triangles through its centre region."""
    rng = np.random.default_rng(seed)
    box = np.array([[x, y, z] for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)])
    box_faces = np.array(
        [
            [0, 1, 3],
            [0, 3, 2],
            [4, 6, 7],
            [4, 7, 5],
            [0, 4, 5],
            [0, 5, 1],
            [2, 3, 7],
            [2, 7, 6],
            [0, 2, 6],
            [0, 6, 4],
            [1, 5, 7],
            [1, 7, 3],
        ]
    )
    a = rng.uniform(-0.5, 0.5, (count, 3))
    vertices = np.vstack([box, a, -a, -a + 1e-4])
    k = 8 + np.arange(count)
    return vertices, np.vstack([box_faces, np.stack([k, k + count, k + 2 * count], 1)])


def cast_ms(vertices, faces, args, cut):
    with _testing.overrides(no_sliver_cutting=not cut):
        result = sd.compute(
            vertices, faces, engine=args.engine, bvh_quality=args.bvh_quality, orientation="as_is"
        )
    return result.timings["cast"] * 1e3, result.raw


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--engine", default="cpu")
    parser.add_argument("--bvh-quality", default="auto", choices=("auto", "high", "fast"))
    args = parser.parse_args()
    cases = [(f"cylinder, {s} sections", *cylinder(s)) for s in (500, 2000, 8000)]
    cases += [(f"needles, {n}", *needles(n)) for n in (2000, 8000)]
    cases += [
        (name, *read_off(DATA / f"{name}.off"))
        for name in ("ChineseDragon-10kv", "armadillo", "bunny00")
    ]
    print(
        f"engine {args.engine}, bvh_quality {args.bvh_quality}, best of {args.rounds} "
        "alternating rounds\n"
    )
    print("| mesh | faces | BVH refs | cast ms uncut | cast ms cut | uncut/cut | values equal |")
    print("|---|---:|---:|---:|---:|---:|---|")
    for name, vertices, faces in cases:
        refs = _testing.bvh_stats(vertices, faces)["triangles"]
        times = {False: [], True: []}
        values = {}
        for _ in range(args.rounds):
            for cut in (False, True):
                ms, values[cut] = cast_ms(vertices, faces, args, cut)
                times[cut].append(ms)
        uncut, cut = min(times[False]), min(times[True])
        print(
            f"| {name} | {len(faces):,} | {refs:,} | {uncut:.1f} | {cut:.1f} | "
            f"{uncut / cut:.2f} | {np.array_equal(values[False], values[True])} |"
        )


if __name__ == "__main__":
    main()
