# SPDX-License-Identifier: GPL-3.0-or-later
"""The ``shape-diameter`` command: the SDF of a mesh file, written back as a coloured mesh.

Needs the ``cli`` extra (trimesh to read and write meshes, tqdm for the progress
bar); both are imported only when the command runs, so ``import shape_diameter``
never needs them.

``--json`` prints one object on stdout: input, faces, vertices (of the mesh as
read), points ("faces" or "vertices"), point_count, rays, cone, sampling, seed,
normalize, smooth, engine, seconds (compute()'s stages: Result.timings), Mrays_per_s
(point_count * rays / seconds["cast"] / 1e6), io_seconds (load, write),
total_seconds (the whole command) and outputs (mesh, values: paths or null).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import logging
import os
import sys
import time
import warnings

import numpy as np

from . import __version__
from .api import MAX_RAYS, compute
from .colormap import colormap
from .output_files import written_whole
from .smoothing import DEVICE_ERRORS

PROG = "shape-diameter"
DEFAULT_SUFFIX = ".sdf.ply"
# Exit statuses: 2 for anything wrong with what the user gave (options, input
# file, output path), as argparse does; 1 when this machine is the problem (a missing
# dependency, an OpenCL device that fails or is too small, memory, a failed write).
EXIT_USAGE = 2
EXIT_ENVIRONMENT = 1


class CommandError(Exception):
    """A failure reported as one line on stderr, exiting with `status`."""

    def __init__(self, message: str, status: int = EXIT_USAGE):
        super().__init__(message)
        self.status = status


class _Parser(argparse.ArgumentParser):
    """argparse reports errors as a usage block plus a message; we promise one line."""

    def error(self, message):
        self.exit(EXIT_USAGE, f"{self.prog}: error: {_one_line(message)}\n")


def _one_line(text) -> str:
    return " ".join(str(text).split())


def _int_in(low: int, high: int):
    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not an integer: {text!r}") from None
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f"must be in [{low}, {high}], got {value}")
        return value

    return parse


def _cone_degrees(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not 0.0 < value < 180.0:
        raise argparse.ArgumentTypeError(f"must be in (0, 180) degrees, got {text}")
    return value


def _positive_float(name: str, high: float):
    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
        if not 0.0 <= value <= high:
            raise argparse.ArgumentTypeError(f"{name} must be in [0, {high:g}], got {text}")
        return value

    return parse


# Each smoothing option of the command line, the method it belongs to and its name in
# shape_diameter.smooth().
SMOOTHING_FLAGS = {
    "k": ("kring", "k"),
    "iterations": ("projected", "iterations"),
    "texture_size": ("texture", "texture_size"),
    "radius": ("texture", "radius"),
}


def default_output(input_path: str) -> str:
    """INPUT with its suffix replaced by .sdf.ply, in the same folder."""
    return os.path.splitext(input_path)[0] + DEFAULT_SUFFIX


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog=PROG,
        description="Compute the Shape Diameter Function (SDF) of a triangle mesh and write "
        "the mesh coloured by it (viridis: thin parts dark purple, thick parts yellow).",
        epilog="Reads OBJ, PLY, OFF, STL, glTF and GLB (polygons are triangulated; the "
        "meshes of a glTF scene are joined). Writes PLY, OBJ, OFF, GLB or STL, chosen by "
        "the output suffix; STL keeps no colour; an existing OUTPUT is overwritten. Exit "
        "status: 0 done, 2 bad option, input or output path, 1 missing dependency, OpenCL "
        "device failure (e.g. too little device memory), out of memory or failed write.",
    )
    parser.add_argument("input", metavar="INPUT", help="mesh file to read")
    parser.add_argument(
        "-o",
        "--output",
        metavar="OUTPUT",
        help=f"coloured mesh to write (default: INPUT with its suffix replaced by "
        f"'{DEFAULT_SUFFIX}', next to INPUT; e.g. cow.obj -> cow{DEFAULT_SUFFIX})",
    )
    parser.add_argument(
        "--rays",
        type=_int_in(1, MAX_RAYS),
        default=30,
        metavar="N",
        help="rays cast per point (default: 30)",
    )
    parser.add_argument(
        "--cone",
        type=_cone_degrees,
        default=120.0,
        metavar="DEG",
        help="full apex angle of the ray cone in degrees (default: 120)",
    )
    parser.add_argument(
        "--points",
        choices=("faces", "vertices"),
        default="faces",
        help="one value per face (coloured per face) or per vertex (default: faces)",
    )
    parser.add_argument(
        "--sampling",
        choices=("fibonacci", "random", "cgal"),
        default="fibonacci",
        help="ray directions and reduction rules (default: fibonacci)",
    )
    parser.add_argument(
        "--seed",
        type=_int_in(0, 2**32 - 1),
        default=0,
        metavar="S",
        help="seed of --sampling random (default: 0)",
    )
    parser.add_argument(
        "--normalize",
        choices=("linear", "log"),
        default="linear",
        help="how values map to colours (default: linear)",
    )
    parser.add_argument(
        "--orientation",
        choices=("auto", "as_is", "flip"),
        default="auto",
        help="auto: turn inside-out parts and stray reversed faces outward; as_is: trust the "
        "winding; flip: reverse every face (default: auto)",
    )
    parser.add_argument(
        "--engine",
        default="auto",
        metavar="ENGINE",
        help="auto (the best OpenCL GPU, else the CPU), cpu, opencl (the best OpenCL device), "
        "opencl:N, opencl:all or opencl:<part of a device name> (default: auto); "
        "--smooth projected and texture run there too",
    )
    parser.add_argument(
        "--accel",
        choices=("bvh", "octree"),
        default="bvh",
        help="acceleration structure: bvh, or the paper's octree (default: bvh)",
    )
    parser.add_argument(
        "--bvh-quality",
        choices=("auto", "high", "fast"),
        default="auto",
        help="high: SAH everywhere (fastest to cast); fast: Morton splits below 1024 "
        "triangles (fastest to build); auto: fast on GPUs at <= 64 rays (default: auto)",
    )
    parser.add_argument(
        "--threads",
        type=_int_in(0, 4096),
        default=0,
        metavar="N",
        help="CPU engine threads, 0 for every core (default: 0)",
    )
    parser.add_argument(
        "--smooth",
        choices=("none", "kring", "projected", "texture"),
        default="none",
        help="smooth the SDF before colouring (paper 4.4): kring = Gaussian over mesh rings, "
        "projected = octree of points moved inward by half their SDF, texture = blur in the "
        "UV layout (needs UVs in INPUT: OBJ vt, glTF TEXCOORD_0 of a primitive with a "
        "material, PLY texture coordinates) (default: none)",
    )
    parser.add_argument(
        "--k",
        type=_int_in(0, 255),
        metavar="K",
        help="--smooth kring: rings around each point (default: from the face count, 2 near "
        "20k faces, 5 at 500k)",
    )
    parser.add_argument(
        "--iterations",
        type=_int_in(0, 1000),
        metavar="N",
        help="--smooth projected: passes (default: 1)",
    )
    parser.add_argument(
        "--texture-size",
        type=_int_in(1, 16384),
        metavar="PX",
        help="--smooth texture: width and height of the texture in texels (default: 1024)",
    )
    parser.add_argument(
        "--radius",
        type=_positive_float("--radius", 16384.0),
        metavar="PX",
        help="--smooth texture: blur radius in texels (default: 2 per 256 texels, 8 at 1024)",
    )
    parser.add_argument(
        "--values",
        metavar="FILE.npy",
        help="also save the SDF (float32, mesh units; smoothed with --smooth) as a .npy "
        "array: one value per face or vertex, in the order they were read from INPUT",
    )
    parser.add_argument(
        "--json",
        action="store_true",
        help="print one JSON object with sizes, options, engine, timings and outputs",
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    return parser


def main(argv=None) -> int:
    """Run the command; returns the exit status (the console script exits with it)."""
    try:
        args = build_parser().parse_args(argv)
    except SystemExit as done:  # --help, --version, or an option error already printed
        return done.code if isinstance(done.code, int) else 0
    try:
        return _run(args)
    except CommandError as exc:
        return _fail(exc, exc.status)
    except ValueError as exc:
        # load_mesh, compute and save_colored report bad input this way.
        return _fail(exc, EXIT_USAGE)
    except OSError as exc:  # e.g. the output could not be written
        return _fail(exc, EXIT_ENVIRONMENT)
    except DEVICE_ERRORS as exc:
        # The device, not the mesh. Its first line: a kernel's build log follows it; the
        # advice is worded for the Python API.
        line = (str(exc) or "OpenCL failed").splitlines()[0]
        return _fail(line.replace("engine='cpu'", "--engine cpu"), EXIT_ENVIRONMENT)
    except MemoryError:
        return _fail("out of memory", EXIT_ENVIRONMENT)
    except KeyboardInterrupt:
        return _fail("interrupted", 130)


def _fail(message, status: int) -> int:
    print(f"{PROG}: error: {_one_line(message)}", file=sys.stderr)
    return status


def _run(args) -> int:
    try:
        from . import mesh_io
    except ImportError as exc:
        raise CommandError(
            f"the command line needs trimesh: pip install 'shape_diameter[cli]' ({exc})",
            EXIT_ENVIRONMENT,
        ) from exc
    # trimesh logs what it skips in odd files; this command reports errors itself.
    logging.getLogger("trimesh").setLevel(logging.CRITICAL + 1)

    smoothing_options = _smoothing_options(args)
    output = args.output or default_output(args.input)
    _check_writable_path(output, mesh_io.WRITE_SUFFIXES)
    if args.values:
        _check_writable_path(args.values, None)
    _check_distinct(args.input, output, args.values)

    started = time.perf_counter()
    with warnings.catch_warnings():
        # A parser warns before it fails on a broken file; the error line says it all.
        warnings.simplefilter("ignore")
        if args.smooth == "texture":
            vertices, triangles, uvs = mesh_io.load_mesh_with_uvs(args.input)
            if uvs is None:
                raise CommandError(
                    f"{args.input}: no UVs for every face (--smooth texture needs OBJ vt, "
                    "glTF TEXCOORD_0 of a primitive with a material (trimesh reads no UVs "
                    "without one), or PLY texture coordinates)"
                )
        else:
            vertices, triangles = mesh_io.load_mesh(args.input)
            uvs = None
    loaded = time.perf_counter()

    with _progress_bar() as progress, warnings.catch_warnings(record=True) as caught, \
            _naming(args.input):
        warnings.simplefilter("always")
        result = compute(
            vertices,
            triangles,
            rays=args.rays,
            cone_angle=args.cone,
            sampling=args.sampling,
            seed=args.seed,
            points=args.points,
            normalize=args.normalize,
            progress=progress,
            orientation=args.orientation,
            engine=args.engine,
            accel=args.accel,
            bvh_quality=args.bvh_quality,
            threads=args.threads,
            smoothing=args.smooth,
            uvs=uvs,
            smoothing_options=smoothing_options,
        )
    computed = time.perf_counter()
    for warning in caught:  # one line each, like the errors
        print(f"{PROG}: warning: {_one_line(warning.message)}", file=sys.stderr)

    with warnings.catch_warnings(record=True) as caught:  # GLB and STL: float32 coordinates
        warnings.simplefilter("always")
        mesh_io.save_colored(output, vertices, triangles, colormap(result.normalized),
                             args.points)
    for warning in caught:
        print(f"{PROG}: warning: {_one_line(warning.message)}", file=sys.stderr)
    if args.values:
        with written_whole(args.values) as temporary, open(temporary, "wb") as stream:
            np.save(stream, np.asarray(result.values, dtype=np.float32))  # (a path gains .npy)
    finished = time.perf_counter()

    # The CLI's own stages, apart from compute()'s: reading and writing files.
    io_seconds = {"load": loaded - started, "write": finished - computed}
    report = _report(args, vertices, triangles, result, output, io_seconds, finished - started)
    if args.json:
        print(json.dumps(report))
    else:
        print(
            f"{args.input}: {report['point_count']} {args.points}, {args.rays} rays, "
            f"{report['total_seconds']:.2f} s on {result.engine} -> {output}"
        )
    return 0


@contextlib.contextmanager
def _naming(path: str):
    """compute()'s ValueErrors (a mesh wider than 1e30, ...) name the file they are about."""
    try:
        yield
    except ValueError as exc:
        raise ValueError(f"{path}: {exc}") from exc


def _smoothing_options(args) -> dict:
    """The smoothing flags given, as smooth() options; a flag of another method is an error."""
    options = {}
    for flag, (method, name) in SMOOTHING_FLAGS.items():
        value = getattr(args, flag)
        if value is None:
            continue
        if args.smooth != method:
            raise CommandError(f"--{flag.replace('_', '-')} applies to --smooth {method}")
        options[name] = value
    return options


def _check_writable_path(path: str, suffixes) -> None:
    """Fail before the long computation, not after it."""
    if suffixes is not None and os.path.splitext(path)[1].lower() not in suffixes:
        raise CommandError(f"{path}: output must end in one of {', '.join(suffixes)}")
    if os.path.isdir(path):
        raise CommandError(f"{path}: is a folder")
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise CommandError(f"{path}: folder {folder} does not exist")


def _check_distinct(source: str, output: str, values) -> None:
    """Outputs are overwritten: never the input, and not one output by the other."""
    if _same_file(output, source):
        raise CommandError(f"{output}: is the input file; give another -o OUTPUT")
    if values and _same_file(values, source):
        raise CommandError(f"{values}: is the input file; give another --values FILE.npy")
    if values and _same_file(values, output):
        raise CommandError(f"{values}: is also the mesh output; give --values another file")


def _same_file(a: str, b: str) -> bool:
    """Whether two paths name one file: the same path once links are resolved, or (hard
    links, case-insensitive file systems) the same existing file."""
    if os.path.realpath(a) == os.path.realpath(b):
        return True
    try:
        return os.path.samefile(a, b)
    except OSError:  # one of them does not exist (yet)
        return False


def _report(args, vertices, triangles, result, output, io_seconds, total_seconds) -> dict:
    """The --json object (documented in the README's command line section)."""
    point_count = len(result.raw)
    timings = {stage: float(seconds) for stage, seconds in result.timings.items()}
    cast = timings.get("cast", timings.get("total", 0.0))
    return {
        "input": args.input,
        "faces": len(triangles),
        "vertices": len(vertices),
        "points": args.points,
        "point_count": point_count,
        "rays": int(result.rays),
        "cone": float(args.cone),
        "sampling": args.sampling,
        "seed": int(args.seed),
        "normalize": args.normalize,
        "smooth": args.smooth,
        "engine": result.engine,
        "flipped_faces": result.flipped_faces,
        "seconds": timings,
        # Rays cast per second over the casting stage alone (or the whole
        # computation where the engine does not time casting separately).
        "Mrays_per_s": point_count * int(result.rays) / cast / 1e6 if cast > 0 else None,
        "io_seconds": io_seconds,
        "total_seconds": total_seconds,
        "outputs": {"mesh": output, "values": args.values},
    }


@contextlib.contextmanager
def _progress_bar():
    """A progress callback for compute(): a tqdm bar on stderr, or a silent one.

    The bar only on a terminal (a bar in a log file is noise) and only after
    half a second, so quick runs print nothing. stdout is never touched. Always
    a callback: native code runs without Python, which takes Ctrl-C (SIGINT) only
    when the callback returns to it, so without one an interrupt would wait for
    the whole computation.
    """

    def silent(fraction: float) -> None:
        pass

    if not sys.stderr.isatty():
        yield silent
        return
    try:
        from tqdm import tqdm
    except ImportError:  # the bar is a nicety; run without it
        yield silent
        return
    with tqdm(
        total=100,
        delay=0.5,
        file=sys.stderr,
        leave=False,
        bar_format="{l_bar}{bar}| {elapsed}<{remaining}",
        desc=PROG,
    ) as bar:

        def update(fraction: float) -> None:
            percent = 100.0 * min(max(float(fraction), 0.0), 1.0)
            if percent > bar.n:
                bar.update(percent - bar.n)

        yield update


if __name__ == "__main__":
    sys.exit(main())
