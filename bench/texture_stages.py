# SPDX-License-Identifier: GPL-3.0-or-later
"""Where texture-space smoothing's time goes, and old against new in one run.

    python bench/texture_stages.py [--engine cpu|opencl:N] [--threads T] [--size S] \\
        [--radius R] [--points faces|vertices] [--repeat N] MESH...
    python bench/texture_stages.py --compare OLD_PYTHONPATH NEW_PYTHONPATH [same options] MESH...

MESH: a name under build/bench-meshes (spot-x64, spot-x256: made by smoothing_bench.py,
with UVs). The field is the distance of each face's centre (or each vertex) from the mesh's
centre: the cost of the method does not depend on the values.

One process: prints, per mesh, smooth()'s wall time (best of --repeat) and the stages of the
fastest call into shape_diameter._core.smooth_texture (its "timings", where the build reports
them). --compare runs this script under each PYTHONPATH in turn ("" for the installed
package), alternating old and new --rounds times, and prints the best of each with the ratio:
the machine may be shared, so only a comparison made in one run means anything.
"""

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

CACHE = Path(__file__).resolve().parents[1] / "build" / "bench-meshes"


def measure(args):
    import shape_diameter as sd
    from shape_diameter import _core

    for name in args.meshes:
        z = np.load(CACHE / f"{name}.npz")
        v, t, uvs = z["vertices"], z["triangles"], z["uvs"]
        if args.points == "faces":
            values = np.linalg.norm(v[t].mean(axis=1) - v.mean(axis=0), axis=1)
        else:
            values = np.linalg.norm(v - v.mean(axis=0), axis=1)
        values = values.astype(np.float32)
        options = {"texture_size": args.size}
        if args.radius is not None:
            options["radius"] = args.radius
        radius = args.radius if args.radius is not None else 2.0 * args.size / 256.0

        def public():
            sd.smooth(v, t, values, "texture", uvs=uvs, points=args.points, threads=args.threads,
                      engine=args.engine, **options)  # fmt: skip

        def core():
            return _core.smooth_texture(
                v, t, values, args.points, uvs.astype(np.float32), args.size, args.size, radius,
                False, 0.1, 2, 1e-6, False, args.threads, None, args.engine,
            )

        public()  # warm: an OpenCL device compiles or loads its program on the first call
        wall, stages = float("inf"), {}
        for _ in range(args.repeat):
            start = time.perf_counter()
            public()
            wall = min(wall, time.perf_counter() - start)
        best = float("inf")
        for _ in range(args.repeat):
            start = time.perf_counter()
            out = core()
            took = time.perf_counter() - start
            if took < best:
                best, stages = took, dict(out.get("timings", {}))
        print(json.dumps({"mesh": name, "faces": len(t), "smooth_ms": wall * 1e3,
                          "core_ms": best * 1e3,
                          "stages_ms": {k: s * 1e3 for k, s in stages.items()}}), flush=True)  # fmt: skip


def compare(args, passthrough):
    versions = {"old": args.compare[0], "new": args.compare[1]}
    best = {}
    for _ in range(args.rounds):
        for label, path in versions.items():
            env = dict(os.environ, PYTHONPATH=path)
            out = subprocess.run([sys.executable, __file__, *passthrough], env=env, check=True,
                                 capture_output=True, text=True).stdout  # fmt: skip
            for line in out.splitlines():
                row = json.loads(line)
                key = (row["mesh"], label)
                if key not in best or row["smooth_ms"] < best[key]["smooth_ms"]:
                    best[key] = row
    print(f"engine {args.engine}, threads {args.threads}, {args.size}x{args.size}, radius "
          f"{args.radius if args.radius is not None else 'default'}, {args.points}; best of "
          f"{args.rounds} rounds x {args.repeat} (ms)")  # fmt: skip
    for name in args.meshes:
        old, new = best[(name, "old")], best[(name, "new")]
        print(f"{name} ({old['faces']:,} faces): smooth() old {old['smooth_ms']:.1f}, new "
              f"{new['smooth_ms']:.1f}, old/new {old['smooth_ms'] / new['smooth_ms']:.2f}")  # fmt: skip
        for label, row in (("old", old), ("new", new)):
            stages = " | ".join(f"{k} {x:.1f}" for k, x in row["stages_ms"].items())
            print(f"  {label}: _core {row['core_ms']:.1f}" + (f": {stages}" if stages else ""))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("meshes", nargs="+")
    parser.add_argument("--engine", default="cpu")
    parser.add_argument("--threads", type=int, default=0)
    parser.add_argument("--size", type=int, default=1024)
    parser.add_argument("--radius", type=float, default=None)
    parser.add_argument("--points", default="faces", choices=("faces", "vertices"))
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--compare", nargs=2, metavar=("OLD_PYTHONPATH", "NEW_PYTHONPATH"))
    parser.add_argument("--rounds", type=int, default=2, help="with --compare: alternations")
    args = parser.parse_args()
    if not args.compare:
        return measure(args)
    passthrough = [a for a in sys.argv[1:]]
    i = passthrough.index("--compare")
    del passthrough[i : i + 3]
    return compare(args, passthrough)


if __name__ == "__main__":
    main()
