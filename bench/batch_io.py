# SPDX-License-Identifier: GPL-3.0-or-later
"""Where one batch input's time goes besides compute(): reading (the file checks, trimesh's
parser, our own conversion and checks), colouring and writing (values .npy, coloured mesh),
against compute(threads=0) on the same mesh, in one run.

Meshes of 52k-1.2M faces (real ones, subdivided 1-to-4) stored as binary PLY, the command
line's own output format, and, with --formats, as OBJ, OFF and STL too. Each stage is timed
single-threaded as the batch runs it, best of --repeat.

    .venv/bin/python bench/batch_io.py [--rays 30] [--repeat 3] [--formats ply,obj] [--no-compute]
"""

from __future__ import annotations

import argparse
import io
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import shape_diameter as sd  # noqa: E402
import trimesh  # noqa: E402
from meshes import DATA, read_off, subdivide  # noqa: E402
from shape_diameter import mesh_io  # noqa: E402
from shape_diameter.colormap import colormap  # noqa: E402
from shape_diameter.mesh_file_checks import check_complete  # noqa: E402

# (mesh, 1-to-4 subdivisions): 52k, 75k, 208k, 302k, 832k, 1.2M faces.
SIZES = (("armadillo", 0), ("bunny00", 0), ("armadillo", 1), ("bunny00", 1), ("armadillo", 2),
         ("bunny00", 2))  # fmt: skip


def best(function, repeat: int):
    """(the fastest of `repeat` calls in seconds, the last call's result)."""
    fastest = float("inf")
    for _ in range(repeat):
        start = time.perf_counter()
        result = function()
        fastest = min(fastest, time.perf_counter() - start)
    return fastest, result


def write_input(path: Path, vertices, triangles) -> None:
    """The mesh as the format its suffix names: binary PLY as the command line writes it,
    OBJ and OFF as text, STL binary (through trimesh)."""
    if path.suffix in (".ply", ".obj", ".off"):
        colors = np.full((len(triangles), 4), 255, dtype=np.uint8)
        mesh_io.save_colored(path, vertices, triangles, colors)
    else:
        trimesh.Trimesh(vertices, triangles, process=False).export(path)


def parser_seconds(path: Path, repeat: int) -> float:
    """trimesh.load alone, as mesh_io calls it (OFF is parsed by mesh_io itself: 0)."""
    if path.suffix == ".off":
        return 0.0
    return best(lambda: trimesh.load(path, process=False, force="scene", skip_materials=True),
                repeat)[0]  # fmt: skip


def stages(path: Path, rays: int, repeat: int, with_compute: bool) -> dict:
    """Seconds of each stage of one input, as batch_job.run_job runs them."""
    seconds = {"checks": best(lambda: check_complete(str(path), path.suffix), repeat)[0]}
    seconds["parser"] = parser_seconds(path, repeat)
    seconds["read"], (vertices, triangles) = best(lambda: mesh_io.load_mesh(path), repeat)
    seconds["ours"] = seconds["read"] - seconds["checks"] - seconds["parser"]
    if with_compute:
        seconds["compute"], result = best(
            lambda: sd.compute(vertices, triangles, rays=rays, engine="cpu", threads=0), 1
        )
        values, normalized = result.values, result.normalized
    else:
        values = np.random.default_rng(0).random(len(triangles), dtype=np.float32)
        normalized = values
    seconds["colour"], colors = best(lambda: colormap(normalized), repeat)

    def save_values():
        npy = io.BytesIO()
        np.save(npy, np.asarray(values, dtype=np.float32))
        with open(path.with_suffix(".sdf.npy"), "wb") as stream:
            stream.write(npy.getbuffer())

    seconds["values"] = best(save_values, repeat)[0]
    out = path.with_name(path.stem + ".sdf.ply")
    seconds["mesh"] = best(
        lambda: mesh_io.save_colored(out, vertices, triangles, colors, "faces"), repeat
    )[0]
    seconds["write"] = seconds["colour"] + seconds["values"] + seconds["mesh"]
    return {"faces": len(triangles), **seconds}


def _share(part: float, compute) -> str:
    return f"{part / compute:.1%}" if compute else "-"


def table(folder: Path, formats, rays: int, repeat: int, with_compute: bool) -> None:
    print("| mesh | faces | read ms (checks / parser / ours) | colour ms | values ms | mesh ms "
          "| compute s | read / compute | write / compute |")  # fmt: skip
    print("|---|---|---|---|---|---|---|---|---|")
    for name, times in SIZES:
        vertices, triangles = read_off(DATA / f"{name}.off")
        for _ in range(times):
            vertices, triangles = subdivide(vertices, triangles)
        computed = None
        for suffix in formats:
            path = folder / f"{name}-x{4**times}.{suffix}"
            write_input(path, vertices, triangles)
            s = stages(path, rays, repeat, with_compute and computed is None)
            computed = s.get("compute", computed)
            print(
                f"| {path.name} | {s['faces']} | {s['read'] * 1e3:.0f} ({s['checks'] * 1e3:.0f}"
                f" / {s['parser'] * 1e3:.0f} / {s['ours'] * 1e3:.0f}) | {s['colour'] * 1e3:.0f}"
                f" | {s['values'] * 1e3:.0f} | {s['mesh'] * 1e3:.0f} | "
                f"{computed if computed else 0:.2f} | {_share(s['read'], computed)} | "
                f"{_share(s['write'], computed)} |",
                flush=True,
            )
            path.unlink()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rays", type=int, default=30)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--formats", default="ply", help="comma separated: ply,obj,off,stl")
    parser.add_argument("--no-compute", action="store_true", help="reading and writing only")
    args = parser.parse_args()
    print(f"{os.cpu_count()} cores; load average {os.getloadavg()[0]:.1f} at the start\n")
    folder = Path(tempfile.mkdtemp(prefix="sdf-batch-io-"))
    try:
        table(folder, args.formats.split(","), args.rays, args.repeat, not args.no_compute)
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    print(f"\nLoad average {os.getloadavg()[0]:.1f} at the end.")


if __name__ == "__main__":
    main()
