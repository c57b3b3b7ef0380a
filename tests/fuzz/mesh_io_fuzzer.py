# SPDX-License-Identifier: GPL-3.0-or-later
"""Fuzzer for the mesh reading path: shape_diameter.mesh_io.load_mesh (trimesh plus our OBJ
pre-pass) and load_mesh_with_uvs, on arbitrary bytes.

An input is a selector byte and a file: the selector's bits 0-2 pick the suffix the bytes
are saved under (SUFFIXES, modulo their count), bit 3 reads with load_mesh_with_uvs.

The contract checked: the only exception is ValueError (a file that cannot be read, holds
no triangles, or has non-finite coordinates or bad indices); a mesh that is returned has
float64 (n, 3) finite vertices, int64 (m, 3) triangles with m >= 1 and every index in
[0, n), and UVs that are None or float32 (m, 3, 2) and finite. Any other exception, a
broken contract (ContractBroken), a hang (-timeout) or memory blow-up (-rss_limit_mb) is a
finding.

    python tests/fuzz/mesh_io_fuzzer.py CORPUS_DIR -max_total_time=60   # fuzz (atheris)
    python tests/fuzz/mesh_io_fuzzer.py FILE...                          # replay inputs

With atheris (pip install atheris) this is coverage-guided libFuzzer, the flags are
libFuzzer's. Without it, --plain runs a plain random-mutation fuzzer seeded from the corpus
(no coverage guidance; much weaker), for the seconds given by -max_total_time.
"""

from __future__ import annotations

import os
import sys
import tempfile

SUFFIXES = (".obj", ".ply", ".off", ".stl", ".glb", ".gltf")
WITH_UVS = 8
# Modules that trimesh imports but files are not read through: left uninstrumented, since
# instrumenting all of trimesh takes 10 s of each run's minute. (atheris takes whole
# packages to include and exact module names to exclude.)
NOT_READING = [
    "boolean",
    "interfaces",
    "interfaces.blender",
    "interfaces.generic",
    "convex",
    "collision",
    "comparison",
    "creation",
    "curvature",
    "decomposition",
    "graph",
    "intersections",
    "permutate",
    "poses",
    "proximity",
    "ray",
    "ray.ray_triangle",
    "ray.ray_util",
    "ray.ray_pyembree",
    "registration",
    "remesh",
    "repair",
    "path",
    "path.path",
    "path.creation",
    "path.arc",
    "path.entities",
    "path.curve",
    "path.raster",
    "path.segments",
    "path.simplify",
    "path.traversal",
    "path.util",
    "path.exchange",
    "path.exchange.export",
    "path.exchange.dxf",
    "path.exchange.svg_io",
    "path.repair",
    "path.polygons",
    "path.exchange.misc",
    "path.exchange.load",
    "sample",
    "exchange.export",
    "exchange.dae",
    "exchange.threemf",
    "exchange.urdf",
    "exchange.binvox",
    "exchange.cascade",
    "exchange.threedxml",
    "exchange.xaml",
    "rendering",
    "primitives",
    "smoothing",
    "nsphere",
    "inertia",
    "voxel",
    "voxel.creation",
    "voxel.base",
    "voxel.morphology",
    "voxel.encoding",
    "voxel.runlength",
    "voxel.ops",
    "voxel.transforms",
]
EXCLUDE = [f"trimesh.{name}" for name in NOT_READING] + [
    "shape_diameter.api",
    "shape_diameter.checks",
    "shape_diameter.engine_choice",
    "shape_diameter.smoothing",
    "shape_diameter.normalization",
]


class ContractBroken(AssertionError):
    """load_mesh returned something its docstring rules out."""


_workdir = None


def _path_for(suffix: str) -> str:
    global _workdir
    if _workdir is None:
        _workdir = tempfile.mkdtemp(prefix="sdf-mesh-io-fuzz-")
    return os.path.join(_workdir, "input" + suffix)


def check_one(data: bytes) -> None:
    """Reads the input as mesh_io would read a file; raises on a finding."""
    import numpy as np
    from shape_diameter import mesh_io

    if not data:
        return
    selector, content = data[0], data[1:]
    suffix = SUFFIXES[(selector & 7) % len(SUFFIXES)]
    path = _path_for(suffix)
    with open(path, "wb") as out:
        out.write(content)
    try:
        if selector & WITH_UVS:
            vertices, triangles, uvs = mesh_io.load_mesh_with_uvs(path)
        else:
            (vertices, triangles), uvs = mesh_io.load_mesh(path), None
    except ValueError:
        return  # the documented refusal
    n, m = len(vertices), len(triangles)
    if not (
        isinstance(vertices, np.ndarray)
        and vertices.dtype == np.float64
        and vertices.shape == (n, 3)
    ):
        raise ContractBroken(
            f"vertices {type(vertices)} {getattr(vertices, 'dtype', None)} "
            f"{getattr(vertices, 'shape', None)}"
        )
    if not (
        isinstance(triangles, np.ndarray)
        and triangles.dtype == np.int64
        and triangles.shape == (m, 3)
        and m >= 1
    ):
        raise ContractBroken(
            f"triangles {getattr(triangles, 'dtype', None)} {getattr(triangles, 'shape', None)}"
        )
    if not np.isfinite(vertices).all():
        raise ContractBroken("a vertex coordinate is not finite")
    if triangles.min() < 0 or triangles.max() >= n:
        raise ContractBroken("a triangle index is outside [0, n)")
    if uvs is not None and not (
        isinstance(uvs, np.ndarray)
        and uvs.dtype == np.float32
        and uvs.shape == (m, 3, 2)
        and np.isfinite(uvs).all()
    ):
        raise ContractBroken(f"uvs {getattr(uvs, 'dtype', None)} {getattr(uvs, 'shape', None)}")


def _quiet():
    """trimesh logs every file it cannot parse; a fuzzer makes millions of them."""
    import logging
    import warnings

    logging.getLogger("trimesh").setLevel(logging.CRITICAL + 1)
    logging.disable(logging.CRITICAL)
    warnings.simplefilter("ignore")


def _atheris_main(argv) -> None:
    import atheris

    with atheris.instrument_imports(include=["trimesh", "shape_diameter"], exclude=EXCLUDE):
        import trimesh  # noqa: F401
        from shape_diameter import mesh_io  # noqa: F401
    _quiet()
    atheris.Setup(argv, check_one)
    atheris.Fuzz()


def _plain_main(argv) -> int:
    """Random mutations of the corpus files (bit flips, byte edits, splices, truncation,
    insertion of interesting tokens), each input run through check_one; the first finding is
    saved as crash-<n> in the current directory (or -artifact_prefix) and ends the run."""
    import random
    import time
    import traceback

    seconds, prefix, dirs, files = 60.0, "./", [], []
    for arg in argv[1:]:
        if arg.startswith("-max_total_time="):
            seconds = float(arg.split("=", 1)[1])
        elif arg.startswith("-artifact_prefix="):
            prefix = arg.split("=", 1)[1]
        elif arg.startswith("-"):
            continue  # libFuzzer flags without meaning here
        elif os.path.isdir(arg):
            dirs.append(arg)
        else:
            files.append(arg)
    _quiet()
    if files:  # replay
        for name in files:
            print(f"replay: {name}", flush=True)
            with open(name, "rb") as stream:
                check_one(stream.read())
        return 0
    seeds = []
    for d in dirs:
        for name in sorted(os.listdir(d)):
            with open(os.path.join(d, name), "rb") as stream:
                seeds.append(stream.read())
    seeds = [s for s in seeds if s] or [b"\x00"]
    tokens = [
        b"nan",
        b"inf",
        b"-1",
        b"0",
        b"1e308",
        b"4294967296",
        b"99999999999",
        b"\n",
        b" ",
        b"/",
        b"f ",
        b"v ",
        b"element vertex ",
        b"property list uchar int ",
        b"binary_little_endian",
        b"\x00\x00\x00\x00",
        b"\xff\xff\xff\xff",
    ]
    rng = random.Random(0)
    runs, deadline = 0, time.monotonic() + seconds
    while time.monotonic() < deadline:
        data = bytearray(rng.choice(seeds))
        for _ in range(rng.randint(1, 8)):
            op = rng.randrange(6)
            pos = rng.randrange(len(data) + 1)
            if op == 0 and data:
                data[min(pos, len(data) - 1)] ^= 1 << rng.randrange(8)
            elif op == 1 and data:
                data[min(pos, len(data) - 1)] = rng.randrange(256)
            elif op == 2:
                data[pos:pos] = rng.choice(tokens)
            elif op == 3 and len(data) > 1:
                del data[pos : pos + rng.randint(1, 64)]
            elif op == 4:
                other = rng.choice(seeds)
                start = rng.randrange(len(other))
                data[pos:pos] = other[start : start + rng.randint(1, 256)]
            else:
                del data[rng.randint(1, max(1, len(data))) :]
        runs += 1
        try:
            check_one(bytes(data))
        except Exception:  # noqa: BLE001 (any exception is a finding)
            path = f"{prefix}crash-{runs}"
            with open(path, "wb") as out:
                out.write(data)
            traceback.print_exc()
            print(f"mesh_io_fuzzer (plain): finding after {runs} inputs, saved to {path}")
            return 1
    print(
        f"mesh_io_fuzzer (plain, random mutation, no coverage guidance): {runs} inputs, "
        f"{seconds:.0f} s, no finding"
    )
    return 0


def main(argv) -> int:
    plain = "--plain" in argv
    argv = [a for a in argv if a != "--plain"]
    if not plain:
        try:
            import atheris  # noqa: F401
        except ImportError:
            print(
                "mesh_io_fuzzer: atheris is not installed (pip install atheris); "
                "running the plain random-mutation fuzzer instead",
                file=sys.stderr,
            )
            plain = True
    if plain:
        return _plain_main(argv)
    _atheris_main(argv)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
