# SPDX-License-Identifier: GPL-3.0-or-later
"""Where k-ring smoothing's time goes, stage by stage, and old against new in one run.

    python bench/kring_stages.py MESH... [--threads T ...] [--k K ...] \\
        [--points faces|vertices] [--repeat N]
    python bench/kring_stages.py MESH... --compare OLD_PYTHONPATH NEW_PYTHONPATH \\
        [--rounds R] [same options]

(MESH first: --threads and --k take several numbers.)

MESH: a name under build/bench-meshes (spot-x64, spot-x256: made by smoothing_bench.py). The
field is the distance of each face's centre (or each vertex) from the mesh's centre: the cost
of the method does not depend on the values. --k -1 is the default k of the mesh's size.

One process: prints a JSON line per mesh, thread count and k: smooth()'s wall time, the wall
time of shape_diameter._testing.smooth_kring and its stages ("mesh" is the conversion of the
arrays; "weld: ..." are parts of "weld"), each the best of --repeat calls, and a hash of the
values. --compare runs this script under each PYTHONPATH in turn, alternating old and new
--rounds times, and prints per stage the best of each: on a shared machine only a comparison
made in one run means anything. A stage that takes as long at 2 threads as at 1 is serial,
and Amdahl says what it costs on 16 cores.
"""

import argparse
import hashlib
import json
import time
from pathlib import Path

import alternate_builds
import numpy as np

CACHE = Path(__file__).resolve().parents[1] / "build" / "bench-meshes"


def field(v, t, points):
    centres = v[t].mean(axis=1) if points == "faces" else v
    return np.linalg.norm(centres - v.mean(axis=0), axis=1).astype(np.float32)


def measure_one(v, t, values, points, k, threads, repeat):
    import shape_diameter as sd
    from shape_diameter import _testing

    wall, core, stages, digest = float("inf"), float("inf"), {}, None
    for _ in range(repeat):
        start = time.perf_counter()
        sd.smooth(v, t, values, "kring", points=points, threads=threads, k=None if k < 0 else k)
        wall = min(wall, time.perf_counter() - start)
        start = time.perf_counter()
        out = _testing.smooth_kring(v, t, values, points, k, 0.0, 0.0, 1e-6, threads, None)
        core = min(core, time.perf_counter() - start)
        # Each stage's best over the calls: the stages of one call are each disturbed at random.
        for stage, seconds in out["timings"].items():
            stages[stage] = min(stages.get(stage, float("inf")), seconds)
        digest = hashlib.sha256(out["values"].tobytes()).hexdigest()[:16]
    return {"smooth_ms": wall * 1e3, "core_ms": core * 1e3,
            "stages_ms": {s: x * 1e3 for s, x in stages.items()}, "values": digest}  # fmt: skip


def measure(args):
    for name in args.meshes:
        z = np.load(CACHE / f"{name}.npz")
        v, t = z["vertices"], z["triangles"].astype(np.int64)
        values = field(v, t, args.points)
        for threads in args.threads:
            for k in args.k:
                row = measure_one(v, t, values, args.points, k, threads, args.repeat)
                row.update(mesh=name, faces=len(t), threads=threads, k=k)
                print(json.dumps(row), flush=True)


def keep_best(best, row):
    """Merges a row into the best so far: each time its minimum."""
    best["smooth_ms"] = min(best["smooth_ms"], row["smooth_ms"])
    best["core_ms"] = min(best["core_ms"], row["core_ms"])
    for stage, ms in row["stages_ms"].items():
        best["stages_ms"][stage] = min(best["stages_ms"].get(stage, float("inf")), ms)
    if best["values"] != row["values"]:
        raise SystemExit(
            f"{row['mesh']}: one build gave different values from one call to the next"
        )
    return best


def print_comparison(old, new):
    print(f"\n{old['mesh']} ({old['faces']:,} faces), {old['threads']} threads, k {old['k']}: "
          f"values {'identical' if old['values'] == new['values'] else 'DIFFERENT'}")  # fmt: skip
    print("| stage | old ms | new ms |")
    print("|---|---:|---:|")
    stages = list(old["stages_ms"]) + [s for s in new["stages_ms"] if s not in old["stages_ms"]]
    for stage in stages:
        cells = [f"{row['stages_ms'][stage]:.1f}" if stage in row["stages_ms"] else "-"
                 for row in (old, new)]  # fmt: skip
        print(f"| {stage} | {cells[0]} | {cells[1]} |")
    for total in ("core_ms", "smooth_ms"):
        print(f"| {total[:-3]}() total | {old[total]:.1f} | {new[total]:.1f} |")


def compare(args):
    best = alternate_builds.best_rows(
        __file__, args, lambda row: (row["mesh"], row["threads"], row["k"]), keep_best
    )
    print(f"{args.points}; each time the best of {args.rounds} rounds x {args.repeat} calls")
    for name in args.meshes:
        for threads in args.threads:
            for k in args.k:
                print_comparison(best[(name, threads, k, "old")], best[(name, threads, k, "new")])


def main():
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("meshes", nargs="+")
    parser.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--k", type=int, nargs="+", default=[-1, 1])
    parser.add_argument("--points", default="faces", choices=("faces", "vertices"))
    parser.add_argument("--repeat", type=int, default=3)
    alternate_builds.add_arguments(parser, rounds=3)
    args = parser.parse_args()
    return compare(args) if args.compare else measure(args)


if __name__ == "__main__":
    main()
