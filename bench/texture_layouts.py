# SPDX-License-Identifier: GPL-3.0-or-later
"""What a UV layout of several pages costs texture smoothing: spot subdivided (spot-x64,
374,784 faces, with UVs; smoothing_bench.py's) smoothed as laid out (one square), with its
UV islands spread over 2 and 4 UDIM tiles, and stacked on a copy of itself (two overlapping
shells, twice the faces), each against the one-square layout in the same run.

    .venv/bin/python bench/texture_layouts.py [--times 3] [--size 1024] [--threads 0] \\
        [--engine cpu] [--repeat 3]

Prints a table: layout, faces, pages (images drawn), best wall time of smooth() over --repeat
(runs alternate between layouts, as the machine may be shared), the UV layout stage (finding
tiles and overlaps), and the ratio to the one-square time.
"""

import argparse
import time

import numpy as np
import shape_diameter as sd
from shape_diameter import _core, _testing
from shape_diameter.smoothing import check_smoothing
from smoothing_bench import spot_mesh


def layouts(v, t, uvs):
    islands = _testing.uv_islands(v, t, uvs, 1e-6)
    out = {"one square": (v, t, uvs)}
    for tiles in (2, 4):
        offset = np.array([[k % 2, k // 2] for k in range(tiles)], dtype=np.float32)
        moved = (uvs + offset[islands % tiles][:, None, :]).astype(np.float32)
        out[f"{tiles} tiles"] = (v, t, moved)
    stacked_v = np.vstack([v, v + [3.0, 0.0, 0.0]])
    out["stacked copy"] = (stacked_v, np.vstack([t, t + len(v)]), np.concatenate([uvs, uvs]))
    return out


def run(v, t, uvs, values, size, threads, engine):
    resolved = check_smoothing("texture", {"texture_size": size}, uvs=uvs, face_count=len(t),
                               vertex_count=len(v), triangles=t)  # fmt: skip
    corners = resolved.pop("uvs")
    start = time.perf_counter()
    out = _core.smooth_field(v, t, values, "faces", "texture", resolved, corners, threads, None,
                             engine, False)  # fmt: skip
    return time.perf_counter() - start, out


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--times", type=int, default=3, help="subdivisions of spot (3: spot-x64)")
    p.add_argument("--size", type=int, default=1024)
    p.add_argument("--threads", type=int, default=0)
    p.add_argument("--engine", default="cpu")
    p.add_argument("--repeat", type=int, default=3)
    args = p.parse_args()
    v, t, uvs = spot_mesh(args.times)
    v, t = np.asarray(v, dtype=np.float64), np.asarray(t, dtype=np.int64)
    rng = np.random.default_rng(3)
    cases = layouts(v, t, uvs)
    best = {name: (float("inf"), None) for name in cases}
    for _ in range(args.repeat):
        for name, (cv, ct, cu) in cases.items():
            values = rng.uniform(0.1, 1.0, len(ct)).astype(np.float32)
            took, out = run(cv, ct, cu, values, args.size, args.threads, args.engine)
            if took < best[name][0]:
                best[name] = (took, out)
    base = best["one square"][0]
    print(f"{'layout':<14}{'faces':>10}{'pages':>7}{'seconds':>10}{'layout s':>10}{'ratio':>8}")
    for name, (took, out) in best.items():
        faces = len(cases[name][1])
        layout = out["timings"].get("uv layout", float("nan"))
        print(f"{name:<14}{faces:>10}{out['pages']:>7}{took:>10.3f}{layout:>10.3f}"
              f"{took / base:>8.2f}")  # fmt: skip
    print(
        f"({args.size}^2 texels, engine {args.engine}, threads {args.threads or 'all'}, "
        f"shape_diameter {sd.__version__})"
    )


if __name__ == "__main__":
    main()
