# SPDX-License-Identifier: GPL-3.0-or-later
"""Times one smoothing method in two builds of shape_diameter in the same run: OLD (the package
the given Python imports, e.g. main's .venv) against NEW (the same Python with PYTHONPATH set
to a staged build), in alternating subprocesses, best of the rounds for each, and checks that
both give the same values. On a shared machine only such same-run ratios mean anything.

    .venv/bin/python bench/smoothing_old_vs_new.py --new build/pyroot \\
        [--method projected] [--engines cpu opencl:0] [--meshes spot-x64 spot-x256] \\
        [--threads 2] [--rounds 5] [--repeat 3] [--option iterations=2]

The field smoothed is the SDF that compute() casts on each mesh (engine 'cpu', 30 rays),
cast once with OLD and cached next to the mesh (build/bench-meshes/<mesh>.sdf.npy).
Meshes as in smoothing_bench.py: spot-xN and armadillo-x16 (made and cached if missing).
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

# One timing in a fresh process: best of `repeat` calls, the values saved for the comparison.
CHILD = r"""
import json, sys, time
import numpy as np
import shape_diameter as sd
mesh, field, out, method, engine, threads, repeat, options = sys.argv[1:9]
z = np.load(mesh)
values = np.load(field)
options = json.loads(options)
best = None
for _ in range(int(repeat)):
    start = time.perf_counter()
    result = sd.smooth(z["vertices"], z["triangles"], values, method, engine=engine,
                       threads=int(threads), **options)
    wall = time.perf_counter() - start
    best = wall if best is None else min(best, wall)
np.save(out, result)
print(json.dumps({"wall": best, "package": sd.__file__}))
"""


def mesh_file(name):
    from meshes import CACHE

    path = CACHE / f"{name}.npz"
    if not path.exists():
        import smoothing_bench as sb

        if name.startswith("spot-x"):
            times = {4**i: i for i in range(1, 6)}[int(name.removeprefix("spot-x"))]
            sb.spot_mesh(times)
        elif name == "armadillo-x16":
            sb.armadillo_x16()
        else:
            raise SystemExit(f"unknown mesh {name}")
    return path


def field_file(python, mesh):
    path = mesh.with_suffix(".sdf.npy")
    if not path.exists():
        code = ("import sys, numpy as np, shape_diameter as sd; z = np.load(sys.argv[1]); "
                "np.save(sys.argv[2], sd.compute(z['vertices'], z['triangles'], "
                "engine='cpu').raw)")  # fmt: skip
        subprocess.run([python, "-c", code, str(mesh), str(path)], check=True, env=old_env())
    return path


def old_env():
    env = dict(os.environ)
    env.pop("PYTHONPATH", None)
    return env


def run(python, env, mesh, field, out, args, engine, options):
    line = subprocess.run(
        [python, "-c", CHILD, str(mesh), str(field), str(out), args.method, engine,
         str(args.threads), str(args.repeat), json.dumps(options)],
        check=True, env=env, capture_output=True, text=True,
    ).stdout.strip().splitlines()[-1]  # fmt: skip
    return json.loads(line)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--new", required=True, help="PYTHONPATH of the new build")
    parser.add_argument("--python", default=sys.executable, help="imports the old package")
    parser.add_argument("--method", default="projected")
    parser.add_argument("--engines", nargs="+", default=["cpu"])
    parser.add_argument("--meshes", nargs="+", default=["spot-x64", "spot-x256"])
    parser.add_argument("--threads", type=int, default=0)
    parser.add_argument("--rounds", type=int, default=5, help="alternations old/new")
    parser.add_argument("--repeat", type=int, default=3, help="calls per process (the best)")
    parser.add_argument("--option", action="append", default=[], help="NAME=JSON value")
    args = parser.parse_args()
    options = {k: json.loads(v) for k, v in (o.split("=", 1) for o in args.option)}
    new_env = dict(os.environ, PYTHONPATH=str(Path(args.new).resolve()))

    print("| mesh | faces | engine | old ms | new ms | new / old | max abs diff |")
    print("|---|---:|---|---:|---:|---:|---:|")
    with tempfile.TemporaryDirectory() as tmp:
        for name in args.meshes:
            mesh = mesh_file(name)
            field = field_file(args.python, mesh)
            faces = len(np.load(mesh)["triangles"])
            for engine in args.engines:
                best = {"old": None, "new": None}
                for _ in range(args.rounds):
                    for who, env in (("old", old_env()), ("new", new_env)):
                        out = Path(tmp) / f"{who}.npy"
                        r = run(args.python, env, mesh, field, out, args, engine, options)
                        if best[who] is None or r["wall"] < best[who]:
                            best[who] = r["wall"]
                diff = float(np.max(np.abs(np.load(Path(tmp) / "old.npy").astype(np.float64)
                                           - np.load(Path(tmp) / "new.npy"))))  # fmt: skip
                print(f"| {name} | {faces:,} | {engine} | {best['old'] * 1e3:.1f} | "
                      f"{best['new'] * 1e3:.1f} | {best['new'] / best['old']:.2f} | {diff:.3g} |",
                      flush=True)  # fmt: skip


if __name__ == "__main__":
    main()
