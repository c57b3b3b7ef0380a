# SPDX-License-Identifier: GPL-3.0-or-later
"""Where projected-points and texture-space smoothing spend their time, alone and inside
compute(), and old against new in one run.

    python bench/smoothing_stages.py [--method texture|projected] [--engine cpu|opencl:N] \\
        [--threads T] [--size S] [--radius R] [--points faces|vertices] [--repeat N] MESH...
    python bench/smoothing_stages.py --compare OLD_PYTHONPATH NEW_PYTHONPATH [same options] MESH...

MESH: a name under build/bench-meshes (spot-x64, spot-x256: made by smoothing_bench.py,
with UVs). The field smoothed is the mesh's SDF (compute() on the same engine, 30 rays).

One process: prints, per mesh, one JSON line: smooth()'s wall time (best of --repeat), the
stages of the fastest call into shape_diameter._testing (its timings), and compute(smoothing=
method)'s cast and smoothing times (best of --repeat each) with smoothing as a percentage of
the cast (the target: at most 10%). Inside compute() the texture method's UV islands
are found while a device casts ('beside cast'). --compare runs this script under each
PYTHONPATH in turn ("" for the installed package), alternating old and new --rounds times,
and prints the best of each with the ratio: the machine may be shared, so only a comparison
made in one run means anything.
"""

import argparse
import json
import sys
import time
from pathlib import Path

import alternate_builds
import numpy as np

CACHE = Path(__file__).resolve().parents[1] / "build" / "bench-meshes"


def best_of(repeat, fn):
    best, out = float("inf"), None
    for _ in range(repeat):
        start = time.perf_counter()
        result = fn()
        took = time.perf_counter() - start
        if took < best:
            best, out = took, result
    return best, out


def measure(args):
    import shape_diameter as sd
    from shape_diameter import _core, _testing

    # Each method alone: in _testing (builds that predate it held them in _core).
    alone = _testing if hasattr(_testing, "smooth_texture") else _core

    for name in args.meshes:
        z = np.load(CACHE / f"{name}.npz")
        v, t = z["vertices"], z["triangles"]
        if args.method == "texture" and "uvs" not in z:
            sys.exit(f"{name} has no UVs: texture smoothing needs a mesh with them (spot-x*)")
        uvs = z["uvs"] if args.method == "texture" else None
        field = sd.compute(v, t, engine=args.engine, points=args.points, threads=args.threads).raw
        options = {}
        if args.method == "texture":
            options = {"texture_size": args.size}
            if args.radius is not None:
                options["radius"] = args.radius
        radius = args.radius if args.radius is not None else 2.0 * args.size / 256.0

        def public():
            return sd.smooth(v, t, field, args.method, uvs=uvs, points=args.points,
                             threads=args.threads, engine=args.engine, **options)  # fmt: skip

        def core():
            if args.method == "texture":
                return alone.smooth_texture(
                    v,
                    t,
                    field,
                    args.points,
                    uvs.astype(np.float32),
                    args.size,
                    args.size,
                    radius,
                    False,
                    0.1,
                    2,
                    1e-6,
                    False,
                    args.threads,
                    None,
                    args.engine,
                )["timings"]
            timings = {}
            arguments = (v, t, field, args.points, 1, 8, 0.002, 1.0, "mean", args.threads, None,
                         args.engine)  # fmt: skip
            try:
                alone.smooth_projected(*arguments, timings)
            except TypeError:  # a build from before projected smoothing reported its stages
                alone.smooth_projected(*arguments)
            return timings

        def inside_compute():
            return sd.compute(
                v,
                t,
                engine=args.engine,
                points=args.points,
                threads=args.threads,
                smoothing=args.method,
                uvs=uvs,
                smoothing_options=options,
            ).timings

        public()  # warm: an OpenCL device compiles or loads its program on the first call
        wall, _ = best_of(args.repeat, public)
        core_s, stages = best_of(args.repeat, core)
        runs = [inside_compute() for _ in range(args.repeat)]
        cast = min(r["cast"] for r in runs)
        fastest = min(runs, key=lambda r: r["smooth"])
        smooth = fastest["smooth"]
        steps = {
            k[len("smooth: ") :]: x * 1e3 for k, x in fastest.items() if k.startswith("smooth: ")
        }
        beside = min(r.get("beside cast", 0.0) for r in runs)
        print(
            json.dumps(
                {
                    "mesh": name,
                    "faces": len(t),
                    "method": args.method,
                    "smooth_ms": wall * 1e3,
                    "core_ms": core_s * 1e3,
                    "stages_ms": {k: s * 1e3 for k, s in stages.items()},
                    "compute_cast_ms": cast * 1e3,
                    "compute_smooth_ms": smooth * 1e3,
                    "compute_beside_cast_ms": beside * 1e3,
                    "compute_smooth_steps_ms": steps,
                    "smooth_percent_of_cast": 100.0 * smooth / cast,
                }
            ),
            flush=True,
        )


def compare(args):
    best = alternate_builds.best_rows(
        __file__,
        args,
        lambda row: (row["mesh"],),
        lambda best, row: row if row["smooth_ms"] < best["smooth_ms"] else best,
    )
    print(f"{args.method}, engine {args.engine}, threads {args.threads}, {args.points}; best of "
          f"{args.rounds} rounds x {args.repeat} (ms)")  # fmt: skip
    for name in args.meshes:
        old, new = best[(name, "old")], best[(name, "new")]
        print(
            f"{name} ({old['faces']:,} faces): smooth() old {old['smooth_ms']:.1f}, new "
            f"{new['smooth_ms']:.1f}, old/new {old['smooth_ms'] / new['smooth_ms']:.2f}"
        )
        for label, row in (("old", old), ("new", new)):
            stages = " | ".join(f"{k} {x:.1f}" for k, x in row["stages_ms"].items())
            steps = " | ".join(
                f"{k} {x:.2f}" for k, x in row.get("compute_smooth_steps_ms", {}).items()
            )
            print(f"  {label}: _testing {row['core_ms']:.1f}" + (f": {stages}" if stages else "") +
                  f"; in compute(): smooth {row['compute_smooth_ms']:.1f} = "
                  f"{row['smooth_percent_of_cast']:.1f}% of the cast" +
                  (f" ({steps})" if steps else ""))  # fmt: skip


def main():
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("meshes", nargs="+")
    parser.add_argument("--method", default="texture", choices=("texture", "projected"))
    parser.add_argument("--engine", default="cpu")
    parser.add_argument("--threads", type=int, default=0)
    parser.add_argument("--size", type=int, default=1024, help="texture: texels a side")
    parser.add_argument("--radius", type=float, default=None, help="texture: blur radius")
    parser.add_argument("--points", default="faces", choices=("faces", "vertices"))
    parser.add_argument("--repeat", type=int, default=3)
    alternate_builds.add_arguments(parser, rounds=2)
    args = parser.parse_args()
    return compare(args) if args.compare else measure(args)


if __name__ == "__main__":
    main()
