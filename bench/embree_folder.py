# SPDX-License-Identifier: GPL-3.0-or-later
"""Our whole compute() (the defaults, CPU engine, every core) against the Embree 3 reference of
the same rule (bench/embree_sdf.cpp: its BVH build and cast, every core) on every mesh of a
folder, in one run: per mesh, interleaved, the median of several rounds; also the cast alone.

    bash scripts/setup_bench.sh        # libembree-dev and build/cpp/bench/embree_sdf
    .venv/bin/python bench/embree_folder.py FOLDER [--rounds 5] [--rays 30]

Ratios are Embree's time over ours: above 1, ours is faster. The whole call is everything
compute() does (checks, orientation, double-sided faces, sampling, the build, the cast, fill,
normalisation); Embree's, its scene's build and its cast (sampling and the reduction are ours,
inside its cast) of the mesh as compute() oriented it, read before the clock starts. `values`
is the median relative difference between the two fields (the same rule: only the casting
differs), a check that both measured the same thing.
"""

import argparse
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import shape_diameter as sd
from shape_diameter.mesh_io import load_mesh

ROOT = Path(__file__).resolve().parents[1]
EMBREE = ROOT / "build" / "cpp" / "bench" / "embree_sdf"
SUFFIXES = {".obj", ".ply", ".off", ".stl", ".glb", ".gltf"}
TIMES = re.compile(r"build ([0-9.]+) s cast ([0-9.]+) s")


def write_off(path: Path, v: np.ndarray, t: np.ndarray) -> None:
    with open(path, "w") as f:
        f.write(f"OFF\n{len(v)} {len(t)} 0\n")
        np.savetxt(f, v, fmt="%.17g")
        np.savetxt(f, np.column_stack([np.full(len(t), 3), t]), fmt="%d")


def ours(v, t, rays):
    start = time.perf_counter()
    result = sd.compute(v, t, rays=rays, engine="cpu")
    return time.perf_counter() - start, result.timings["cast"], result.raw


def embree(off: Path, rays: int, embree_sdf: Path, out: Path):
    done = subprocess.run([str(embree_sdf), str(off), str(rays), str(out)],
                          capture_output=True, text=True, check=True)  # fmt: skip
    build, cast = map(float, TIMES.search(done.stderr).groups())
    return build + cast, cast, np.loadtxt(out, dtype=np.float32)


def compare(meshes, rounds, rays, embree_sdf, tmp):
    """Per mesh: the whole call's and the cast's seconds of every round, and the fields."""
    keys = ("ours", "ours cast", "embree", "embree cast")
    rows = {name: {"faces": len(t), **{k: [] for k in keys}} for name, _, t, _ in meshes}
    for r in range(rounds):
        for name, v, t, off in meshes:
            runs = [("ours", ours, (v, t, rays)),
                    ("embree", embree, (off, rays, embree_sdf, tmp / "values.txt"))]  # fmt: skip
            for label, run, arguments in runs if r % 2 == 0 else runs[::-1]:  # who goes first
                whole, cast, values = run(*arguments)
                rows[name][label].append(whole)
                rows[name][f"{label} cast"].append(cast)
                rows[name][f"{label} values"] = values
            print(f"round {r + 1}/{rounds}: {name}", file=sys.stderr, flush=True)
    return rows


def print_table(rows, rays):
    print("| mesh | faces | ours ms | Embree ms | whole: Embree/ours | ours cast ms | "
          "Embree cast ms | cast: Embree/ours | values |")  # fmt: skip
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    ratios = []
    for name, row in rows.items():
        m = {k: statistics.median(row[k]) for k in ("ours", "ours cast", "embree", "embree cast")}
        a, b = row["ours values"], row["embree values"]
        both = (b >= 0) & (a > 0)
        difference = float(np.median(np.abs(a[both] - b[both]) / a[both])) if both.any() else 0.0
        ratios.append((m["embree"] / m["ours"], name))
        print(f"| {name} | {row['faces']:,} | {m['ours'] * 1e3:.0f} | {m['embree'] * 1e3:.0f} | "
              f"{m['embree'] / m['ours']:.2f} | {m['ours cast'] * 1e3:.0f} | "
              f"{m['embree cast'] * 1e3:.0f} | {m['embree cast'] / m['ours cast']:.2f} | "
              f"{difference:.1e} |")  # fmt: skip
    worst = min(ratios)
    median = statistics.median(r for r, _ in ratios)
    print(
        f"\n{rays} rays. Whole call, Embree's time over ours: median {median:.2f}, worst "
        f"{worst[0]:.2f} ({worst[1]}); the target: at least 1.2 on every mesh, median 1.5: "
        f"{'met' if worst[0] >= 1.2 and median >= 1.5 else 'not met'}."
    )


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder", type=Path)
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--rays", type=int, default=30)
    parser.add_argument("--embree", type=Path, default=EMBREE, help="the embree_sdf program")
    args = parser.parse_args()
    if not args.embree.exists():
        sys.exit(f"{args.embree} not found: run bash scripts/setup_bench.sh")
    paths = sorted(p for p in args.folder.iterdir() if p.suffix.lower() in SUFFIXES)
    if not paths:
        sys.exit(f"no mesh file in {args.folder}")
    with tempfile.TemporaryDirectory() as folder:
        tmp = Path(folder)
        meshes = []
        for path in paths:
            v, t = load_mesh(path)
            # Embree casts the mesh as compute() oriented it (a mesh wound inside out, turned
            # outward): the same rays on the same surface.
            reversed_faces = sd.compute(v, t, rays=1, engine="cpu").reversed_faces
            wound = t.copy()
            if reversed_faces is not None:
                wound[reversed_faces] = wound[reversed_faces][:, [0, 2, 1]]
            off = tmp / f"{path.stem}.off"
            write_off(off, v, wound)
            meshes.append((path.name, v, t, off))
        rows = compare(meshes, args.rounds, args.rays, args.embree, tmp)
    print(
        f"{sd.engines()[0]['description']} (CPU engine) against Embree 3, median of "
        f"{args.rounds} rounds, interleaved"
    )
    print_table(rows, args.rays)


if __name__ == "__main__":
    main()
