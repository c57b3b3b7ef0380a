# SPDX-License-Identifier: GPL-3.0-or-later
"""How far each smoothing method moves a clean SDF, and how much noise it removes, per mesh.

    .venv/bin/python bench/smoothing_fidelity.py [--noise 0.2] [--psb DIR] [MESH ...]

For each mesh (by default the real meshes of tests/data, and with --psb the Princeton
Segmentation Benchmark meshes DIR/off/*.off): the clean field is compute()'s unsmoothed SDF
(CPU engine, defaults). Per method, with its defaults (projected points also by the paper's
rule, `rule="paper"`):
- shift: the median over faces of |smooth(clean) - clean| / clean: how far the method moves a
  field that needs no smoothing (the paper's purpose is removing noise, not reshaping);
- noisy: the median relative error to the clean field of the clean field times
  (1 + noise * N(0, 1)) (seeded, clipped at 0), before smoothing;
- smoothed: the same error after smoothing the noisy field; gain: noisy / smoothed (above 1,
  the method removed noise; below 1, its result lies farther from the clean field than the
  noisy input did).
Texture smoothing runs on meshes with UVs only. Points: faces.
"""

import argparse
import sys
from pathlib import Path

import numpy as np
import shape_diameter as sd
from shape_diameter.mesh_io import load_mesh_with_uvs

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "tests" / "data"
DEFAULT_MESHES = ["armadillo.off", "bunny00.off", "horse.ply", "fandisk.obj", "cow.obj",
                  "spot.obj", "teapot.obj", "ChineseDragon-10kv.off"]  # fmt: skip
# (label, method, options): each method with its defaults, and projected points by the paper's
# rule too (the default is the local rule).
METHODS = (("kring", "kring", {}), ("projected", "projected", {}),
           ("projected, paper", "projected", {"rule": "paper"}),
           ("bilateral", "bilateral", {}), ("texture", "texture", {}))  # fmt: skip


def relative_error(field: np.ndarray, clean: np.ndarray) -> float:
    kept = clean > 0
    return float(np.median(np.abs(field[kept] - clean[kept]) / clean[kept]))


def rows_of(name, v, t, uvs, noise, rng):
    clean = sd.compute(v, t, engine="cpu").raw.astype(np.float64)
    noisy = np.maximum(clean * (1.0 + noise * rng.standard_normal(len(clean))), 0.0)
    before = relative_error(noisy, clean)
    for label, method, options in METHODS:
        if method == "texture" and uvs is None:
            continue
        extra = {"uvs": uvs, **options} if method == "texture" else options
        smoothed = [
            sd.smooth(v, t, field, method, points="faces", engine="cpu", **extra)
            for field in (clean, noisy)
        ]
        shift = relative_error(smoothed[0].astype(np.float64), clean)
        after = relative_error(smoothed[1].astype(np.float64), clean)
        yield name, len(t), label, shift, before, after


def meshes(args):
    paths = [Path(m) for m in args.meshes] or [DATA / m for m in DEFAULT_MESHES]
    if args.psb:
        folder = args.psb / "off" if (args.psb / "off").is_dir() else args.psb
        paths += sorted(folder.glob("*.off"), key=lambda p: int(p.stem))
    for path in paths:
        v, t, uvs = load_mesh_with_uvs(path)
        has_uvs = uvs is not None and np.ptp(np.asarray(uvs)) > 0
        yield path.stem, v, t, (uvs if has_uvs else None)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("meshes", nargs="*")
    parser.add_argument("--noise", type=float, default=0.2)
    parser.add_argument("--psb", type=Path, help="a Princeton Segmentation Benchmark folder")
    args = parser.parse_args()
    rng = np.random.default_rng(0)
    print(f"noise {args.noise:.0%} of each value (Gaussian); medians over faces\n")
    print("| mesh | faces | method | shift | noisy | smoothed | gain |")
    print("|---|---:|---|---:|---:|---:|---:|")
    summary = {label: [] for label, _, _ in METHODS}
    for name, v, t, uvs in meshes(args):
        for row in rows_of(name, v, t, uvs, args.noise, rng):
            mesh, faces, method, shift, before, after = row
            summary[method].append((shift, before / after))
            print(f"| {mesh} | {faces:,} | {method} | {shift:.1%} | {before:.1%} | "
                  f"{after:.1%} | {before / after:.2f} |", flush=True)  # fmt: skip
        print(f"done: {name}", file=sys.stderr, flush=True)
    print("\n| method | median shift | median gain | meshes |")
    print("|---|---:|---:|---:|")
    for method, values in summary.items():
        if values:
            shifts, kept = zip(*values)
            print(f"| {method} | {np.median(shifts):.1%} | {np.median(kept):.2f} | {len(values)} |")


if __name__ == "__main__":
    main()
