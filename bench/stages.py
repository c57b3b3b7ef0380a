# SPDX-License-Identifier: GPL-3.0-or-later
"""Where compute()'s time goes: each stage of one call (the fastest of --repeat by wall time)
for the benchmark's largest meshes, with each orientation ('auto', 'as_is') and bvh_quality
('auto', 'high'); and old against new in one run.

    python bench/stages.py [ENGINE [MESH,MESH]] [--rays R] [--repeat N]
    python bench/stages.py --compare OLD_PYTHONPATH NEW_PYTHONPATH [same arguments]

Stages overlap where the work does: the BVH builds while the mesh is oriented and sampled
('build' is its own time, 'build wait' what it added after 'prepare'; on OpenCL the points'
upload also overlaps it). --compare runs this script under each PYTHONPATH in turn ("" for
the installed package), alternating old and new --rounds times, and prints the best of each:
on a shared machine only a comparison made in one run means anything."""

import argparse
import json
import os
import sys
import time

sys.path.insert(0, os.path.dirname(__file__))
import alternate_builds  # noqa: E402
from meshes import NAMES, benchmark_meshes  # noqa: E402

SETTINGS = (("auto", "auto"), ("auto", "high"), ("as_is", "auto"), ("as_is", "high"))


def measure(args):
    import shape_diameter as sd

    for name, v, f in benchmark_meshes():
        if name not in args.meshes:
            continue
        for orientation, quality in SETTINGS:
            best, wall = None, None
            for _ in range(args.repeat):
                t0 = time.perf_counter()
                r = sd.compute(
                    v,
                    f,
                    rays=args.rays,
                    engine=args.engine,
                    orientation=orientation,
                    bvh_quality=quality,
                )
                took = (time.perf_counter() - t0) * 1e3
                if best is None or took < wall:
                    best, wall = r, took
            row = {
                "mesh": name,
                "faces": len(f),
                "engine": args.engine,
                "orientation": orientation,
                "bvh_quality": quality,
                "wall_ms": wall,
                "stages_ms": {k: x * 1e3 for k, x in best.timings.items()},
            }
            if args.json:
                print(json.dumps(row), flush=True)
            else:
                print(describe(row), flush=True)


def describe(row):
    stages = " ".join(f"{k} {x:.1f}" for k, x in row["stages_ms"].items())
    return (
        f"{row['mesh']} ({row['faces']:,} faces) {row['engine']} "
        f"orientation={row['orientation']} bvh_quality={row['bvh_quality']}: "
        f"wall {row['wall_ms']:.0f} ms | {stages}"
    )


def compare(args):
    sys.argv.append("--json")  # what each build's run is given: rows to merge
    best = alternate_builds.best_rows(
        __file__,
        args,
        lambda row: (row["mesh"], row["orientation"], row["bvh_quality"]),
        lambda best, row: row if row["wall_ms"] < best["wall_ms"] else best,
    )
    print(
        f"engine {args.engine}, {args.rays} rays; best of {args.rounds} rounds x "
        f"{args.repeat} calls (ms)"
    )
    keys = sorted({k[:-1] for k in best}, key=lambda k: (k[0], SETTINGS.index(k[1:])))
    for key in keys:
        old, new = best[key + ("old",)], best[key + ("new",)]
        print(f"old/new {old['wall_ms'] / new['wall_ms']:.2f}")
        print(f"  old: {describe(old)}")
        print(f"  new: {describe(new)}")


def main():
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("engine", nargs="?", default="opencl")
    parser.add_argument(
        "meshes",
        nargs="?",
        default="armadillo-x16,bunny00-x16",
        type=lambda s: s.split(","),
        help=f"comma-separated, of: {', '.join(NAMES)}",
    )
    parser.add_argument("--rays", type=int, default=30)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--json", action="store_true", help="one JSON line per row")
    alternate_builds.add_arguments(parser, rounds=2)
    args = parser.parse_args()
    unknown = [name for name in args.meshes if name not in NAMES]
    if unknown:
        parser.error(f"unknown mesh {', '.join(unknown)}; the meshes: {', '.join(NAMES)}")
    import shape_diameter as sd

    if (
        args.engine != "auto"
        and args.engine not in [e["name"] for e in sd.engines()]
        and not args.engine.startswith("opencl")
    ):
        parser.error(
            f"unknown engine {args.engine!r}; here: {', '.join(e['name'] for e in sd.engines())}"
        )
    return compare(args) if args.compare else measure(args)


if __name__ == "__main__":
    main()
