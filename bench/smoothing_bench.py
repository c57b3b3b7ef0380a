# SPDX-License-Identifier: GPL-3.0-or-later
"""Smoothing benchmark (CPU): the paper's Table 3 (k-ring, k = 1..8), Table 4 (texture
2048x2048, radius 2..64), projected points, the growth with the face count, and each method's
time against the ray-casting time of the same engine on the same mesh (the target: at
1M faces, at most 10% of casting). Prints the tables and writes them into bench/RESULTS.md
under "## Smoothing (CPU)".

    .venv/bin/python bench/smoothing_bench.py            # everything (meshes up to 1.5M faces)
    .venv/bin/python bench/smoothing_bench.py --quick    # up to 375k faces, one repeat
    .venv/bin/python bench/smoothing_bench.py --opencl opencl:0 [--quick]

--opencl ENGINE times instead the OpenCL versions (projected points, texture space) on that
device next to the CPU versions in the same run, each against the cast time of its own engine,
and writes them under "## Smoothing (OpenCL)" (k-ring has no OpenCL version).

Meshes: spot (tests/data/spot.obj, 5,856 faces, with UVs) subdivided 1-to-4 with its UVs
(x64: 374,784 faces; x256: 1,499,136), and armadillo subdivided x16 (832,000 faces), as the
paper's 500k-face Stanford Dragon is not in the repository. The field smoothed is the SDF
that compute() casts on the mesh (30 rays, 120 degrees, engine 'cpu').
"""

import argparse
import datetime
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import shape_diameter as sd
from meshes import CACHE, DATA, ROOT, read_off, subdivide
from shape_diameter.mesh_io import load_mesh_with_uvs

from bench import machine_line, write_section

KRING_K = range(1, 9)
TEXTURE_RADII = (2, 4, 8, 16, 32, 64)
TITLE = "Smoothing (CPU)"


def subdivide_with_uvs(vertices, triangles, uvs):
    """meshes.subdivide, the per-corner UVs split the same way (a child corner at an edge
    midpoint takes the mean of that edge's two corner UVs in the parent face)."""
    v, t = subdivide(vertices, triangles)
    a, b, c = uvs[:, 0], uvs[:, 1], uvs[:, 2]
    ab, bc, ca = (a + b) / 2, (b + c) / 2, (c + a) / 2
    children = [np.stack(x, axis=1) for x in ((a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca))]
    return v, t, np.concatenate(children).astype(np.float32)


def spot_mesh(times):
    """spot subdivided `times` times (x 4^times faces), with UVs; cached in build/."""
    cached = CACHE / f"spot-x{4**times}.npz"
    if cached.exists():
        z = np.load(cached)
        return z["vertices"], z["triangles"], z["uvs"]
    v, t, uv = load_mesh_with_uvs(DATA / "spot.obj")
    for _ in range(times):
        v, t, uv = subdivide_with_uvs(v, t, uv)
    CACHE.mkdir(parents=True, exist_ok=True)
    np.savez(cached, vertices=v, triangles=t, uvs=uv)
    return v, t, uv


def armadillo_x16():
    cached = CACHE / "armadillo-x16.npz"
    if cached.exists():
        z = np.load(cached)
        return z["vertices"], z["triangles"]
    v, t = read_off(DATA / "armadillo.off")
    for _ in range(2):
        v, t = subdivide(v, t)
    CACHE.mkdir(parents=True, exist_ok=True)
    np.savez(cached, vertices=v, triangles=t)
    return v, t


def best_of(repeat, fn):
    """Fastest of `repeat` runs (the machine is shared: the minimum is the least disturbed)."""
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - start)
    return min(times), out


class Mesh:
    # Casting runs this many times; the fastest cast time is the one compared with smoothing
    # (the best of several runs too), so that load on a shared machine biases neither.
    cast_repeat = 2

    def __init__(self, name, vertices, triangles, uvs=None, threads=0, engine="cpu"):
        self.name, self.v, self.t, self.uvs = name, vertices, triangles, uvs
        casts = []
        for _ in range(self.cast_repeat):
            result = sd.compute(vertices, triangles, engine=engine, threads=threads)
            casts.append(result.timings["cast"])
        self.sdf, self.cast, self.engine = result.raw, min(casts), result.engine
        print(f"# {name}: {len(triangles):,} faces, cast {self.cast:.2f} s on {self.engine}",
              file=sys.stderr, flush=True)  # fmt: skip

    def smooth(self, method, repeat, threads, engine="cpu", **options):
        if method == "texture":
            options["uvs"] = self.uvs
        return best_of(repeat, lambda: sd.smooth(self.v, self.t, self.sdf, method,
                                                  threads=threads, engine=engine,
                                                  **options))  # fmt: skip

    def smoothing_in_compute(self, method, repeat, threads, engine):
        """compute(smoothing=method)'s 'smooth' stage, the fastest of `repeat` calls."""
        uvs = self.uvs if method == "texture" else None
        return min(sd.compute(self.v, self.t, engine=engine, threads=threads, smoothing=method,
                              uvs=uvs).timings["smooth"] for _ in range(repeat))  # fmt: skip


def ms(seconds):
    return f"{seconds * 1e3:,.0f}"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="meshes up to 375k faces, 1 run")
    parser.add_argument("--repeat", type=int, default=3, help="runs per timing (the fastest)")
    parser.add_argument("--cast-repeat", type=int, default=2, help="casts per mesh (the fastest)")
    parser.add_argument("--threads", type=int, default=0, help="CPU threads, 0 for all")
    parser.add_argument("--opencl", metavar="ENGINE", help="time the OpenCL versions on ENGINE")
    parser.add_argument("--title", default="Smoothing (OpenCL)",
                        help="with --opencl: the RESULTS.md section to write")  # fmt: skip
    parser.add_argument("--out", default=str(ROOT / "bench" / "RESULTS.md"))
    args = parser.parse_args()
    repeat = 1 if args.quick else args.repeat
    Mesh.cast_repeat = 1 if args.quick else args.cast_repeat
    threads = args.threads
    if args.opencl:
        return opencl_main(args, repeat, threads)

    spot64 = Mesh("spot-x64", *spot_mesh(3), threads=threads)
    big = [] if args.quick else [
        Mesh("armadillo-x16", *armadillo_x16(), threads=threads),
        Mesh("spot-x256", *spot_mesh(4), threads=threads),
    ]  # fmt: skip
    table3 = [spot64] + big[:1]

    lines = []
    # Table 3.
    header = " | ".join(f"{m.name} ({len(m.t) / 1e3:,.0f}k faces)" for m in table3)
    lines += ["### k-ring on the mesh (paper's Table 3)", "",
              "Seconds per call, faces rings (faces sharing a vertex), vertices merged first. "
              "Paper (Stanford Dragon, 500k faces, one CPU core of an i5 2.67 GHz, 2015): "
              "1.76 s at k = 1, 5.02 s at 3, 10.8 s at 5, 26.6 s at 8.", "",
              f"| k | {header} |", "|---:|" + "---:|" * len(table3)]  # fmt: skip
    for k in KRING_K:
        cells = [f"{m.smooth('kring', repeat, threads, k=k)[0]:.3f}" for m in table3]
        lines.append(f"| {k} | " + " | ".join(cells) + " |")
    defaults = ", ".join(f"{m.name}: k = {sd.smoothing.default_k(len(m.t))}" for m in table3)
    lines += ["", f"Default k ({defaults}).", ""]

    # Table 4.
    texture_meshes = [spot64] + big[1:]
    header = " | ".join(f"{m.name} ({len(m.t) / 1e3:,.0f}k faces)" for m in texture_meshes)
    lines += [
        "### Texture space, 2048 x 2048 (paper's Table 4)",
        "",
        "Seconds per call: rasterise, 2-texel margin, island-masked separable Gaussian, "
        "read back per face. Paper (Dragon 500k, CPU): 6.32 s at radius 2 to 15.8 s at "
        "64; its OpenCL: 0.08 to 0.16 s.",
        "",
        f"| radius (texels) | {header} |",
        "|---:|" + "---:|" * len(texture_meshes),
    ]
    for radius in TEXTURE_RADII:
        cells = [f"{m.smooth('texture', repeat, threads, texture_size=2048, radius=radius)[0]:.3f}"
                 for m in texture_meshes]  # fmt: skip
        lines.append(f"| {radius} | " + " | ".join(cells) + " |")
    lines.append("")

    # Projected points.
    lines += ["### Projected points", "",
              "Seconds per call (octree of the points moved inward by half their SDF; the "
              "default rule 'local': depth 16, branching above 0.001% of the points and while "
              "the mean SDF is at most 16 times the node, each point gathers the nodes within "
              "a twentieth of its SDF; the paper's rule: depth 8, 0.2%, 1 times, the whole SDF). "
              "Paper: 0.58 s (GPU) to 3.39 s (CPU) at 500k faces (Table 1, smoothing column).",
              "", "| mesh | faces | 1 iteration | 2 iterations | 1 iteration, branch on min | "
              "the paper's rule |", "|---|---:|---:|---:|---:|---:|"]  # fmt: skip
    for m in [spot64] + big:
        one = m.smooth("projected", repeat, threads)[0]
        two = m.smooth("projected", repeat, threads, iterations=2)[0]
        by_min = m.smooth("projected", repeat, threads, branch_on="min")[0]
        paper = m.smooth("projected", repeat, threads, rule="paper")[0]
        lines.append(f"| {m.name} | {len(m.t):,} | {one:.3f} | {two:.3f} | {by_min:.3f} | "
                     f"{paper:.3f} |")  # fmt: skip
    lines.append("")

    # Growth with the face count (linear time): spot x4 .. x256 at fixed options.
    lines += ["### Growth with the face count", "",
              "Milliseconds per call at fixed options (k-ring k = 3; projected 1 iteration; "
              "texture 1024, radius 8), and microseconds per face.", "",
              "| mesh | faces | k-ring ms | us/face | projected ms | us/face | texture ms | "
              "us/face |", "|---|---:|---:|---:|---:|---:|---:|---:|"]  # fmt: skip
    growth = [(f"spot-x{4**i}", i) for i in (1, 2, 3)] + ([] if args.quick else [("spot-x256", 4)])
    for name, times in growth:
        m = next((x for x in [spot64] + big if x.name == name), None)
        m = m or Mesh(name, *spot_mesh(times), threads=threads)
        cells = []
        for method, options in (("kring", {"k": 3}), ("projected", {}),
                                ("texture", {"texture_size": 1024, "radius": 8})):  # fmt: skip
            seconds = m.smooth(method, repeat, threads, **options)[0]
            cells += [ms(seconds), f"{seconds / len(m.t) * 1e6:.2f}"]
        lines.append(f"| {name} | {len(m.t):,} | " + " | ".join(cells) + " |")
    lines.append("")

    # Against casting.
    lines += ["### Against ray casting on the same engine", "",
              "Each method with its default options (k-ring: k from the face count; projected: "
              "1 iteration; texture: 1024 x 1024, radius 8) over compute()'s cast time on the "
              "same mesh (timings['cast'], 30 rays, CPU engine, both at full thread count). "
              "Target: at most 10% "
              "at 1M faces; CGAL's post-processing takes 74% of its casting time there.", "",
              "| mesh | faces | cast s | k-ring s (k) | % | projected s | % | texture s | % |",
              "|---|---:|---:|---:|---:|---:|---:|---:|---:|"]  # fmt: skip
    for m in [spot64] + big:
        k = sd.smoothing.default_k(len(m.t))
        kring = m.smooth("kring", repeat, threads)[0]
        projected = m.smooth("projected", repeat, threads)[0]
        texture = m.smooth("texture", repeat, threads)[0] if m.uvs is not None else None
        cells = [f"{kring:.3f} ({k})", f"{100 * kring / m.cast:.1f}",
                 f"{projected:.3f}", f"{100 * projected / m.cast:.1f}"]  # fmt: skip
        cells += ([f"{texture:.3f}", f"{100 * texture / m.cast:.1f}"] if texture is not None
                  else ["(no UVs)", ""])  # fmt: skip
        lines.append(f"| {m.name} | {len(m.t):,} | {m.cast:.2f} | " + " | ".join(cells) + " |")
    lines.append("")

    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True,
                            text=True, cwd=ROOT).stdout.strip()  # fmt: skip
    load = ", ".join(f"{x:.1f}" for x in os.getloadavg())
    section = [f"## {TITLE}", "",
               f"{machine_line()}; {spot64.engine}; {datetime.date.today().isoformat()}, "
               f"commit {commit}; best of {repeat} run(s) per smoothing timing and of "
               f"{Mesh.cast_repeat} per cast; load average at the end "
               f"{load} (the machine is shared: timings are noisy, ratios to casting measured "
               "minutes apart). `bench/smoothing_bench.py`.", ""] + lines  # fmt: skip
    print("\n".join(section))
    write_section(Path(args.out), TITLE, section)


def opencl_main(args, repeat, threads):
    """The OpenCL versions against the CPU versions (same run), and against casting."""
    engine = args.opencl
    device = next((e for e in sd.engines() if e["name"] == engine), None)
    described = device["description"] if device else engine
    meshes = [Mesh("spot-x64", *spot_mesh(3), threads=threads)]
    if not args.quick:
        meshes.append(Mesh("spot-x256", *spot_mesh(4), threads=threads))
    # Compile (or load) the device's program before any timing.
    sd.smooth(meshes[0].v, meshes[0].t, meshes[0].sdf, "projected", engine=engine)
    lines = ["### Texture space, 2048 x 2048 (paper's Table 4), CPU and OpenCL", "",
             "Seconds per smooth() call (on OpenCL, drawing, the 2-texel dilation, both blur "
             "passes and reading face values back run on the device; the UV islands are found "
             "on the host). Paper (Dragon 500k): CPU 6.32 s at radius 2 to 15.8 s at 64; its "
             "OpenCL 0.08 to 0.16 s.", "",
             "| radius (texels) | " + " | ".join(f"{m.name} CPU | {m.name} OpenCL"
                                               for m in meshes) + " |",
             "|---:|" + "---:|---:|" * len(meshes)]  # fmt: skip
    for radius in TEXTURE_RADII:
        cells = []
        for m in meshes:
            for e in ("cpu", engine):
                seconds = m.smooth("texture", repeat, threads, engine=e, texture_size=2048,
                                   radius=radius)[0]  # fmt: skip
                cells.append(f"{seconds:.3f}")
        lines.append(f"| {radius} | " + " | ".join(cells) + " |")
    lines += [
        "",
        "### Projected points, CPU and OpenCL",
        "",
        "Seconds per call, 1 iteration (on OpenCL the points, the octree and the gather "
        "all run on the device; the points' frames are made on the host). Paper: 0.58 s "
        "(GPU) to 3.39 s (CPU) at 500k faces.",
        "",
        "| mesh | faces | CPU | OpenCL | OpenCL, 2 iterations | CPU, the paper's rule | "
        "OpenCL, the paper's rule |",
        "|---|---:|---:|---:|---:|---:|---:|",
    ]
    for m in meshes:
        cpu = m.smooth("projected", repeat, threads)[0]
        opencl = m.smooth("projected", repeat, threads, engine=engine)[0]
        two = m.smooth("projected", repeat, threads, engine=engine, iterations=2)[0]
        paper = [m.smooth("projected", repeat, threads, engine=e, rule="paper")[0]
                 for e in ("cpu", engine)]  # fmt: skip
        lines.append(f"| {m.name} | {len(m.t):,} | {cpu:.3f} | {opencl:.3f} | {two:.3f} | "
                     f"{paper[0]:.3f} | {paper[1]:.3f} |")  # fmt: skip
    lines += ["", "### Against ray casting on the same OpenCL engine", "",
              "Defaults (projected: the local rule, 1 iteration; texture: 1024 x 1024, "
              "radius 8), over "
              f"compute(engine={engine!r})'s cast time on the same mesh: smooth() alone, and "
              "compute(smoothing=...)'s 'smooth' stage (there the texture's UV islands are found "
              "while the device casts, and the projected points' frames uploaded).", "",
              "| mesh | faces | OpenCL cast s | projected s | % | in compute() s | % | "
              "texture s | % | in compute() s | % |",
              "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]  # fmt: skip
    for m in meshes:
        cast = Mesh(m.name, m.v, m.t, m.uvs, threads=threads, engine=engine).cast
        cells = [f"{cast:.3f}"]
        for method in ("projected", "texture"):
            alone = m.smooth(method, repeat, threads, engine=engine)[0]
            inside = m.smoothing_in_compute(method, repeat, threads, engine)
            cells += [f"{alone:.3f}", f"{100 * alone / cast:.1f}", f"{inside:.3f}",
                      f"{100 * inside / cast:.1f}"]  # fmt: skip
        lines.append(f"| {m.name} | {len(m.t):,} | " + " | ".join(cells) + " |")
    lines.append("")
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True,
                            text=True, cwd=ROOT).stdout.strip()  # fmt: skip
    load = ", ".join(f"{x:.1f}" for x in os.getloadavg())
    title = args.title
    section = [f"## {title}", "",
               f"{machine_line()}; {engine}: {described}; CPU versions on "
               f"{meshes[0].engine}; {datetime.date.today().isoformat()}, commit {commit}; best "
               f"of {repeat} run(s) per timing; load average at the end {load} (shared "
               "machine: timings are noisy). `bench/smoothing_bench.py --opencl "
               f"{engine}`.", ""] + lines  # fmt: skip
    print("\n".join(section))
    write_section(Path(args.out), title, section)


if __name__ == "__main__":
    main()
