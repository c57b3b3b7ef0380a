# SPDX-License-Identifier: GPL-3.0-or-later
"""The benchmark: the same meshes and options (30 rays, 120 degrees) through our CPU engine,
our OpenCL engine on every device (BVH and octree), CGAL's sdf_values and an Embree 3 caster
of our rule, in one run on one machine. Prints a table and writes it into bench/RESULTS.md.

    .venv/bin/python bench/bench.py                 # everything (CGAL up to 100k faces)
    .venv/bin/python bench/bench.py --quick         # no 1.2M-face mesh
"""

import argparse
import datetime
import json
import os
import platform
import re
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import shape_diameter as sd
from meshes import CACHE, ROOT, benchmark_meshes, off_path
from shape_diameter import _testing

BUILD = ROOT / "build" / "cpp"


def run(cmd, **kw):
    return subprocess.run(cmd, capture_output=True, text=True, check=True, **kw)


def ours(mesh_npz, engine, accel, rays, values_path):
    # OpenCL runs twice: the reported run is the faster, without the one-off compile.
    repeat = "2" if engine.startswith("opencl") else "1"
    out = run(
        [
            sys.executable,
            str(Path(__file__).with_name("run_one.py")),
            str(mesh_npz),
            str(values_path),
            engine,
            accel,
            str(rays),
            repeat,
        ]
    )
    return json.loads(out.stdout.strip().splitlines()[-1])


def reference(binary, off, rays, values_path):
    """Runs a reference program; returns (seconds of its SDF call, values)."""
    done = run([str(binary), str(off), str(rays), str(values_path)])
    match = re.search(r"(?:took|cast) ([0-9.]+) s", done.stderr)
    return float(match.group(1)), np.loadtxt(values_path)


def pearson(a, b):
    ok = (a > 0) & (b > 0) & np.isfinite(a) & np.isfinite(b)
    return float(np.corrcoef(a[ok], b[ok])[0, 1])


def machine_line():
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as cpuinfo:
            for line in cpuinfo:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return f"{cpu}, {os.cpu_count()} cores, {platform.system()} {platform.release()}"


def octree_depth_table(name, vertices, triangles):
    """The paper's Table 2: octree build time against maximum depth (the build alone)."""
    rows = []
    for depth in range(2, 15, 2):
        stats = _testing.octree_stats(
            np.asarray(vertices, dtype=np.float64), np.asarray(triangles, dtype=np.int64), depth, 8
        )
        rows.append((depth, stats["seconds"] * 1e3, stats["nodes"], stats["leaf_words"]))
    lines = [
        f"Octree build time against maximum depth ({name}, {len(triangles):,} faces, "
        "leaf size 8, one thread; paper's Table 2: 13.9 s at depth 14 to 0.06 s at "
        "depth 2 on 500k faces)",
        "",
        "| max depth | build ms | nodes | leaf words |",
        "|---:|---:|---:|---:|",
    ]
    lines += [f"| {d} | {ms:.0f} | {n:,} | {w:,} |" for d, ms, n, w in rows]
    return lines


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="skip the 1.2M-face mesh")
    parser.add_argument(
        "--depth-table",
        action="store_true",
        help="also time the octree build against its depth (paper's Table 2)",
    )
    parser.add_argument("--rays", type=int, default=30)
    parser.add_argument(
        "--cgal-max-faces",
        type=int,
        default=100_000,
        help="run CGAL on meshes up to this size (it takes minutes beyond)",
    )
    parser.add_argument(
        "--engines",
        default="",
        help="comma-separated engines (default: cpu and every OpenCL device)",
    )
    parser.add_argument("--only", default="", help="comma-separated mesh names to run")
    parser.add_argument("--title", default="", help="section title in RESULTS.md")
    parser.add_argument("--out", default=str(ROOT / "bench" / "RESULTS.md"))
    args = parser.parse_args()

    engines = (
        args.engines.split(",")
        if args.engines
        else (["cpu"] + [e["name"] for e in sd.engines() if e["name"].startswith("opencl")])
    )
    cgal = BUILD / "tests" / "reference" / "cgal_sdf"
    embree = BUILD / "bench" / "embree_sdf"
    rows, notes = [], []
    tmp = Path(tempfile.mkdtemp(prefix="sdf-bench-"))
    meshes = benchmark_meshes(largest=not args.quick)
    only = set(filter(None, args.only.split(",")))
    for name, vertices, triangles in meshes:
        if only and name not in only:
            continue
        faces = len(triangles)
        npz = CACHE / f"{name}.npz"
        if not npz.exists():
            np.savez(npz, vertices=vertices, triangles=triangles)
        off = off_path(name, vertices, triangles)
        cgal_s = cgal_values = None
        if cgal.exists() and faces <= args.cgal_max_faces:
            cgal_s, cgal_values = reference(cgal, off, args.rays, tmp / "cgal.txt")
            rows.append(
                dict(
                    mesh=name,
                    faces=faces,
                    engine="CGAL sdf_values",
                    accel="AABB",
                    build=None,
                    cast=cgal_s * 1e3,
                    total=cgal_s * 1e3,
                    mrays=faces * args.rays / cgal_s / 1e6,
                )
            )
        embree_mrays = None
        if embree.exists():
            embree_s, _ = reference(embree, off, args.rays, tmp / "embree.txt")
            embree_mrays = faces * args.rays / embree_s / 1e6
            rows.append(
                dict(
                    mesh=name,
                    faces=faces,
                    engine="Embree 3 (our rule)",
                    accel="BVH",
                    cast=embree_s * 1e3,
                    total=None,
                    mrays=embree_mrays,
                )
            )
        for engine in engines:
            for accel in ("bvh", "octree"):
                if engine == "cpu" and accel == "octree" and faces > 300_000:
                    continue  # the CPU octree is a reference for the kernels, not a fast path
                r = ours(npz, engine, accel, args.rays, tmp / "ours.npy")
                t = r["timings"]
                cast = t["cast"]
                row = dict(
                    mesh=name,
                    faces=faces,
                    engine=r["engine"].split(" (")[0],
                    accel=accel,
                    # The host's tree, or the one a GPU makes ('build (device)').
                    build=t.get("build", t.get("build (device)", 0.0)) * 1e3,
                    cast=cast * 1e3,
                    total=r["wall"] * 1e3,
                    mrays=faces * args.rays / cast / 1e6,
                    peak=r["peak_mib"],
                    device=r["device_mib"],
                )
                if engine.startswith("opencl"):
                    row["upload"] = t.get("upload", 0) * 1e3
                    row["download"] = t.get("download", 0) * 1e3
                if cgal_s:
                    row["x_cgal"] = cgal_s / r["wall"]
                    row["r_cgal"] = pearson(np.load(tmp / "ours.npy"), cgal_values)
                if embree_mrays:
                    row["x_embree"] = row["mrays"] / embree_mrays
                rows.append(row)
                print(json.dumps({**row, "timings": t}), flush=True)

    def fmt(v, spec):
        return "—" if v is None else format(v, spec)

    header = (
        "| mesh | faces | engine | accel | build ms | cast ms | reduce ms | smoothing ms | "
        "total ms | Mrays/s | × CGAL | ÷ Embree | r vs CGAL | peak host MiB | device MiB |"
    )
    lines = [header, "|" + "---|" * 15]
    for r in rows:
        lines.append(
            f"| {r['mesh']} | {r['faces']:,} | {r['engine']} | {r['accel']} | "
            f"{fmt(r.get('build'), '.0f')} | {fmt(r.get('cast'), '.0f')} | "
            f"{'in cast' if 'peak' in r else '—'} | — | {fmt(r.get('total'), '.0f')} | "
            f"{fmt(r.get('mrays'), '.2f')} | {fmt(r.get('x_cgal'), '.1f')} | "
            f"{fmt(r.get('x_embree'), '.2f')} | {fmt(r.get('r_cgal'), '.3f')} | "
            f"{fmt(r.get('peak'), '.0f')} | {fmt(r.get('device'), '.0f')} |"
        )
    if args.depth_table:
        big = next(m for m in meshes if m[0] == "armadillo-x16")
        notes += [""] + octree_depth_table(*big)
    title = args.title or f"{machine_line()}"
    section = (
        [
            f"## {title}",
            "",
            f"Date {datetime.date.today()}, shape_diameter {sd.__version__}, "
            f"{args.rays} rays, 120°. "
            f"Command: `{' '.join([Path(sys.executable).name] + sys.argv)}`.",
            f"Machine: {machine_line()}. Devices: "
            + "; ".join(f"{e['name']} = {e.get('device', e['description'])}" for e in sd.engines())
            + ".",
            "",
            "Times are wall-clock milliseconds of one run (OpenCL: the faster of two, so without "
            "the one-off kernel compile). total = the whole compute() call from numpy arrays to "
            "numpy values; cast includes the fused reduction. × CGAL = CGAL's time / our total; "
            "÷ Embree = our casting rate / Embree's on the same rule; r = Pearson correlation "
            "with CGAL's values (different outlier rules: 0.94-0.995 expected). Peak host MiB "
            "includes Python and numpy (~60 MiB).",
            "",
        ]
        + lines
        + notes
        + [""]
    )
    print("\n".join(section))
    write_section(Path(args.out), title, section)


def write_section(path, title, section):
    """Replaces this machine's section of RESULTS.md, keeping the others."""
    text = path.read_text() if path.exists() else "# Benchmark results\n\n"
    parts = re.split(r"(?m)^(?=## )", text)
    parts = [p for p in parts if not p.startswith(f"## {title}\n")]
    path.write_text("".join(parts).rstrip() + "\n\n" + "\n".join(section))


if __name__ == "__main__":
    main()
