# SPDX-License-Identifier: GPL-3.0-or-later
"""The ``shape-diameter`` command: the SDF of a mesh file, written back as a coloured mesh.

Needs the ``cli`` extra (trimesh to read and write meshes, tqdm for the progress
bar); both are imported only when the command runs, so ``import shape_diameter``
never needs them.

``--json`` prints one object per input on a line of stdout, when that input is done:
status ("ok" or "error"), error, exit_status, warnings, input, faces, vertices (of the mesh as
read), points ("faces" or "vertices"), point_count, rays, cone, sampling, seed, normalize,
smooth, engine, flipped_faces and twin_faces (Result's), seconds (compute()'s stages:
Result.timings), Mrays_per_s (points cast * rays / seconds["cast"] / 1e6), io_seconds (load,
write), total_seconds (the whole input) and outputs (mesh, values: paths or null); an input
that failed has status, error, exit_status, warnings, input and outputs only. With
``--scheduler`` (inputs computed by Dask workers: shape_diameter.distributed) each object
also has worker, the address of the worker that computed it (or null).

The console script enters through ``_shape_diameter_entry`` and console_main(), which take
Ctrl-C over (see console_main); main() called from Python leaves signals alone.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import logging
import os
import signal
import sys

from . import __version__, _core
from .api import MAX_RAYS, _check_engine, engines
from .batch_job import (
    SEGMENT_DEFAULTS,
    error_report,
    failure,
    naming_a_file,
    one_line,
    run_job,
    skipped_report,
)
from .cli_jobs import DEFAULT_SUFFIX, EXIT_ENVIRONMENT, EXIT_USAGE, CommandError, plan

PROG = "shape-diameter"
EXIT_INTERRUPTED = 130  # 128 + SIGINT, as shells report a run killed by Ctrl-C
EXIT_STDOUT_CLOSED = 141  # 128 + SIGPIPE: what `... | head` leaves a command that goes on


class _StdoutClosed(Exception):
    """Standard output's reader went away (`shape-diameter ... --json | head -1`): the run
    stops quietly, as programs killed by SIGPIPE do, instead of a traceback, or every later input
    reported as failed though its files were written."""


class _StdoutFailed(Exception):
    """Writing to standard output failed otherwise (a full disk behind `> file`): the run
    stops with one line saying so, instead of a traceback with --json, or without it the
    input being computed named as what failed, though its files were written."""


def _say(text: str) -> None:
    """A line on standard output."""
    try:
        print(text, flush=True)
    except BrokenPipeError as exc:
        raise _StdoutClosed() from exc
    except OSError as exc:
        raise _StdoutFailed(exc.strerror or str(exc)) from exc


class _Parser(argparse.ArgumentParser):
    """argparse reports errors as a usage block plus a message; we promise one line."""

    def error(self, message):
        self.exit(EXIT_USAGE, f"{self.prog}: error: {one_line(message)}\n")


# The library's warnings name its Python arguments; on the command line they are options.
_OPTION_SPELLING = {
    "orientation='as_is'": "--orientation as_is",
    "orientation='flip'": "--orientation flip",
    "; 'auto' turns": "; --orientation auto turns",
    "a smaller texture_size": "a smaller --texture-size",
    " and valid_rays is 0 everywhere": "",
}


def _in_option_spelling(message: str) -> str:
    for python, option in _OPTION_SPELLING.items():
        message = message.replace(python, option)
    return message


class _ListEngines(argparse.Action):
    """--list-engines: what --engine takes on this machine, one line each (with --json, each
    engines() entry as a JSON object), then exit; the note on 'auto' goes to stderr, so that
    stdout holds the engines alone (`| awk '{print $1}'` must not list 'auto' too). It
    runs as it is parsed (no INPUT needed): --json is looked for in the parser's arguments."""

    def __init__(self, option_strings, dest, **kwargs):
        super().__init__(option_strings, dest, nargs=0, default=argparse.SUPPRESS, **kwargs)

    def __call__(self, parser, namespace, values, option_string=None):
        found = engines()
        width = max(len(engine["name"]) for engine in found)
        # (argparse takes unambiguous abbreviations: --js is --json)
        as_json = any(
            len(a) > 2 and "--json".startswith(a) for a in getattr(parser, "arguments", ())
        )
        try:
            for engine in found:
                _say(
                    json.dumps(engine)
                    if as_json
                    else f"{engine['name']:<{width}}  {engine['type']}  {engine['description']}"
                )
            if not as_json:
                print(
                    "auto picks the best OpenCL GPU, else cpu; opencl the best OpenCL device"
                    + (
                        "; opencl:all shares the work between the devices"
                        if sum(e["name"].startswith("opencl:") for e in found) > 1
                        else ""
                    ),
                    file=sys.stderr,
                )
        except _StdoutClosed:
            _quiet_stdout()
            parser.exit(EXIT_STDOUT_CLOSED)
        except _StdoutFailed as exc:
            _quiet_stdout()
            parser.exit(EXIT_ENVIRONMENT, f"{PROG}: error: standard output: cannot write ({exc})\n")
        parser.exit()


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


def _positive_float(high: float):
    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
        if not 0.0 <= value <= high:
            raise argparse.ArgumentTypeError(f"must be in [0, {high:g}], got {text}")
        return value

    return parse


def _share(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not 0.0 <= value < 1.0:
        raise argparse.ArgumentTypeError(f"must be a share in [0, 1) (0.01: 1%), got {text}")
    return value


# Each smoothing option of the command line, the method it belongs to and its name in
# shape_diameter.smooth().
SMOOTHING_FLAGS = {
    "k": ("kring", "k"),
    "iterations": ("projected", "iterations"),
    "rule": ("projected", "rule"),
    "texture_size": ("texture", "texture_size"),
    "radius": ("texture", "radius"),
}


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog=PROG,
        description="Compute the Shape Diameter Function (SDF) of a triangle mesh and write "
        "the mesh coloured by it (viridis: thin parts dark purple, thick parts yellow).",
        epilog="Reads OBJ, PLY, OFF, STL, glTF and GLB (polygons are triangulated; the "
        "meshes of a glTF scene are joined). Several INPUTs are computed one after the other "
        "in one process; a file that fails is reported in one line and the others go on. "
        "Writes PLY, OBJ, OFF, GLB or STL, chosen by the output suffix; STL keeps no colour; "
        "an existing OUTPUT is overwritten. Exit status: 0 done, 2 bad option (an --engine "
        "no device here matches: refused before any input is read), input or output path, 1 "
        "missing dependency, OpenCL missing for --engine opencl..., OpenCL device failure "
        "(e.g. too little device memory), out of memory, failed write or a standard output "
        "that cannot be written; with several inputs, the status of the first that failed; "
        "on Ctrl-C the command is killed by SIGINT (status 130 in the shell).",
    )
    parser.add_argument(
        "input",
        metavar="INPUT",
        nargs="+",
        help="mesh file to read; several are computed in turn, each written next to itself; "
        "a folder stands for its mesh files (with -r, its subfolders' too), skipping *.sdf.* "
        "files (this command's outputs)",
    )
    parser.add_argument(
        "-o",
        "--output",
        metavar="OUTPUT",
        help=f"coloured mesh to write, for a single INPUT (default: INPUT with its suffix "
        f"replaced by '{DEFAULT_SUFFIX}', next to INPUT; e.g. cow.obj -> cow{DEFAULT_SUFFIX})",
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
        default=None,  # 0; None tells that it was not given (_check_combinations)
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
        default=None,  # auto; None tells that it was not given (_check_combinations)
        help="high: SAH everywhere (fastest to cast); fast: Morton splits below 1024 "
        "triangles (fastest to build); auto: fast on GPUs at <= 64 rays (default: auto)",
    )
    parser.add_argument(
        "--threads",
        type=_int_in(0, 4096),
        default=0,
        metavar="N",
        help="CPU engine threads, 0 for every core this process may use (default: 0)",
    )
    parser.add_argument(
        "--smooth",
        choices=("none", "kring", "projected", "texture", "bilateral"),
        default="none",
        help="smooth the SDF before colouring (paper 4.4): kring = Gaussian over mesh rings, "
        "projected = octree of points moved inward by half their SDF, texture = blur in the "
        "UV layout (needs UVs in INPUT: OBJ vt, glTF TEXCOORD_0 of a primitive with a "
        "material, PLY texture coordinates), bilateral = CGAL's filter over rings of edge "
        "neighbours (--points faces) (default: none)",
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
        "--rule",
        choices=("local", "paper"),
        help="--smooth projected: 'local' (default: a sphere of a twentieth of each value over "
        "fine leaves, keeps a clean field) or 'paper' (the paper's sphere of the whole value)",
    )
    parser.add_argument(
        "--texture-size",
        type=_int_in(1, 16384),
        metavar="PX",
        help="--smooth texture: width and height of the texture in texels (default: 1024)",
    )
    parser.add_argument(
        "--radius",
        type=_positive_float(16384.0),
        metavar="PX",
        help="--smooth texture: blur radius in texels (default: 2 per 256 texels, 8 at 1024)",
    )
    parser.add_argument(
        "--values",
        metavar="FILE.npy",
        help="also save the SDF (float32, mesh units; smoothed with --smooth) as a .npy "
        "array: with --points faces one value per triangle, in INPUT's face order, a polygon "
        "of k corners giving k-2 consecutive rows (shape_diameter.load_mesh(INPUT, "
        "source_faces=True) gives each row's face); with --points vertices one per vertex, in "
        "INPUT's order (STL: positions merged, by first use)",
    )
    parser.add_argument(
        "--segment",
        nargs="?",
        const=5,
        type=_int_in(1, 256),
        metavar="K",
        help="also split the mesh into parts by thickness (shape_diameter.segment, K clusters, "
        "default 5): colour the output mesh by segment instead of by SDF and save the labels "
        "(int32 per triangle, INPUT's face order) next to it with .segments.npy in place of "
        "its suffix (cow.obj -> cow.sdf.segments.npy); needs --points faces",
    )
    parser.add_argument(
        "--smoothness",
        type=_positive_float(1e6),
        metavar="LAMBDA",
        help="--segment: weight of cutting edges against the cluster fit (default: 0.26)",
    )
    parser.add_argument(
        "--segment-mode",
        choices=("auto", "cgal"),
        help="--segment: auto (the graph cut run until no move helps), or cgal (CGAL 5.5's "
        "segmentation_from_sdf_values exactly) (default: auto)",
    )
    parser.add_argument(
        "--min-part-area",
        type=_share,
        metavar="SHARE",
        help="--segment: a minimum part size, as a share of the mesh's area in [0, 1) (0.01: "
        "1%%): a smaller segment joins the neighbour it shares the longest boundary with; a "
        "separate solid stays whole (default: 0, off)",
    )
    parser.add_argument(
        "--segments",
        type=_int_in(1, 4096),
        metavar="N",
        help="--segment: the number of segments wanted: clusters 2-9 and the smoothness x 1, "
        "0.4 and 2 are searched for it, the nearest count kept (default: K clusters decide)",
    )
    parser.add_argument(
        "--output-dir",
        metavar="DIR",
        help="write each input's outputs into DIR (made if missing) instead of next to the "
        "input, same names (DIR/cow.sdf.ply); of two inputs of one name, the second fails",
    )
    parser.add_argument(
        "-r",
        "--recursive",
        action="store_true",
        help="a folder input stands for the meshes of its subfolders too (not through links "
        "to folders); with --output-dir, each output goes to the same subfolder of DIR "
        "(DIR/a/cow.sdf.ply for FOLDER/a/cow.obj)",
    )
    parser.add_argument(
        "--skip-existing",
        action="store_true",
        help="leave out an input whose outputs (the mesh, and the values with --save-values "
        "or --values) exist already, as after an interrupted batch: outputs are written whole, "
        "the mesh and its values together, so an existing one is finished",
    )
    parser.add_argument(
        "--save-values",
        action="store_true",
        help="save each input's values as --values does, next to its output with .npy in "
        "place of the output's suffix (cow.obj -> cow.sdf.npy); for several inputs",
    )
    parser.add_argument(
        "--json",
        action="store_true",
        help="print one JSON object per input, one a line, when it is done: status ('ok' "
        "or 'error'), error, warnings, sizes, options, engine, timings and outputs",
    )
    parser.add_argument(
        "-q",
        "--quiet",
        action="store_true",
        help="no progress bar and no line per input done; warnings and errors still go to "
        "stderr, --json to stdout",
    )
    parser.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="send the inputs to a running Dask scheduler (tcp://host:8786), one task per "
        "mesh, instead of computing them here: its workers read the inputs and write the "
        "outputs at the same paths (a shared filesystem); lines and --json objects come as "
        "meshes finish (needs the distributed extra)",
    )
    parser.add_argument(
        "--gpu",
        action="store_true",
        help="with --scheduler: each mesh holds one GPU unit of a worker that declares them "
        "(dask worker --nthreads 3 --resources GPU=3: its meshes cast in turn); without it, "
        "--engine auto runs on the workers' CPUs",
    )
    parser.add_argument(
        "--list-engines",
        action=_ListEngines,
        help="list the engines --engine takes here, one a line (with --json, "
        "one JSON object each), and exit",
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    return parser


def main(argv=None, *, interrupts=None) -> int:
    """Run the command; returns the exit status (130 after Ctrl-C: KeyboardInterrupt).

    `interrupts`: the console script's _Interrupts (console_main), which take SIGINT over;
    without them (a call from Python) the process's signal handling is left alone.
    """
    try:
        parser = build_parser()
        parser.arguments = sys.argv[1:] if argv is None else list(map(str, argv))
        args = parser.parse_args(argv)
    except SystemExit as done:  # --help, --version, or an option error already printed
        return done.code if isinstance(done.code, int) else 0
    try:
        return _run(args, interrupts or _Interrupts([]))
    except CommandError as exc:
        return _fail(exc, exc.status)
    except KeyboardInterrupt:
        return _fail("interrupted", EXIT_INTERRUPTED)
    except _StdoutClosed:
        _quiet_stdout()
        return EXIT_STDOUT_CLOSED
    except _StdoutFailed as exc:
        _quiet_stdout()
        return _fail(
            f"standard output: cannot write ({exc}); the outputs of the inputs "
            "reported before were written",
            EXIT_ENVIRONMENT,
        )
    finally:
        if interrupts is not None:
            interrupts.disarm()


def _quiet_stdout() -> None:
    """Python flushes stdout again at exit: point it at nothing, so no second error."""
    with contextlib.suppress(OSError, ValueError):
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())


def _open_closed_streams() -> None:
    """A program started with standard output or error closed (`2>&-`, a daemon's wrapper) has
    None for them in Python: its messages then go nowhere instead of the run failing on its
    first (exit status 1, no output written, no word)."""
    for name in ("stdout", "stderr"):
        if getattr(sys, name) is None:
            setattr(sys, name, open(os.devnull, "w"))  # noqa: SIM115 (the process's own)


def console_main(pending=None) -> int:
    """The command as a program (the console script, ``python -m shape_diameter``): main()
    on sys.argv, and after Ctrl-C, once outputs are cleaned up and the one-line message is
    out, death by SIGINT, so that a shell running it in a loop stops (its status reads 130).
    An exit status of 130 would not do: bash goes on with a loop whose command exited so.

    `pending`: the list the entry point's SIGINT handler has been appending to while the
    modules were imported (see _shape_diameter_entry); None where it could not take SIGINT.
    """
    _open_closed_streams()
    interrupts = _Interrupts([] if pending is None else pending)
    if not interrupts.take_over():
        return main(interrupts=None)
    status = main(interrupts=interrupts)
    if not interrupts.pending:
        return status
    if status != EXIT_INTERRUPTED:  # it came after the last check: still, the loop stops
        _fail("interrupted", EXIT_INTERRUPTED)
    return _die_by(interrupts.pending[0])


class _Interrupts:
    """SIGINT for the console script. Every SIGINT is recorded; while armed (the command's
    own work, not imports: trimesh's imports catch BaseException, and a KeyboardInterrupt
    raised in them was swallowed and the run went on) it also raises KeyboardInterrupt, and
    check() raises it for one that was recorded, held or swallowed since."""

    def __init__(self, pending):
        self.pending = pending
        self.armed = False

    def _handle(self, signum, frame):
        self.pending.append(signum)
        if self.armed:
            raise KeyboardInterrupt

    def take_over(self) -> bool:
        """Install the handler (held, not armed); False where signals cannot be taken. SIGTERM
        and SIGHUP (`timeout`, batch schedulers, a closed terminal) stop the run as Ctrl-C
        does, outputs cleaned up: otherwise they leave temporary files behind."""
        try:
            signal.signal(signal.SIGINT, self._handle)
            for name in ("SIGTERM", "SIGHUP"):
                if hasattr(signal, name):
                    signal.signal(getattr(signal, name), self._handle)
        except (ValueError, OSError):  # not the main thread
            return False
        return True

    def arm(self) -> None:
        self.armed = True
        self.check()

    def disarm(self) -> None:
        self.armed = False

    def check(self) -> None:
        """Raise KeyboardInterrupt if SIGINT came (a check point of the command's own)."""
        if self.pending:
            raise KeyboardInterrupt

    def checked(self, progress):
        """The progress callback, checking first: native code sees Ctrl-C only through it."""

        def callback(fraction):
            self.check()
            progress(fraction)

        return callback


def _die_by(signum) -> int:
    """Death by the signal that stopped the run (SIGINT, SIGTERM or SIGHUP), as a shell
    expects of a program it interrupted."""
    with contextlib.suppress(OSError, ValueError):  # e.g. a closed pipe
        sys.stdout.flush()
    with contextlib.suppress(OSError, ValueError):
        sys.stderr.flush()
    if os.name == "posix":
        signal.signal(signum, signal.SIG_DFL)
        os.kill(os.getpid(), signum)
    return 128 + int(signum)  # where the signal did not end the process


def _fail(message, status: int) -> int:
    print(f"{PROG}: error: {one_line(message)}", file=sys.stderr, flush=True)
    return status


def _run(args, interrupts) -> int:
    try:
        from . import mesh_io
    except ImportError as exc:
        raise CommandError(
            f"the command line needs trimesh: pip install 'shape_diameter[cli]' ({exc})",
            EXIT_ENVIRONMENT,
        ) from exc
    if not args.quiet and sys.stderr.isatty():
        with contextlib.suppress(ImportError):  # the progress bar's, imported while held
            import tqdm  # noqa: F401
    # trimesh logs what it skips in odd files; this command reports errors itself.
    logging.getLogger("trimesh").setLevel(logging.CRITICAL + 1)
    interrupts.arm()  # a Ctrl-C held during the imports stops the run here

    _check_combinations(args)
    _refuse_unusable_engine(args.engine, here=args.scheduler is None)
    _smoothing_options(args)  # (its errors, before any work)
    jobs = plan(args, mesh_io.WRITE_SUFFIXES)
    if args.scheduler is not None:
        return _run_on_scheduler(args, jobs)
    several = len(jobs) > 1 or any(os.path.isdir(source) for source in args.input)
    first_failure = 0
    for job in jobs:
        warned = []
        try:
            if job.problem is not None:
                raise CommandError(job.problem)
            if job.done:
                report = _skipped(args, job)
                if args.json:
                    _say(json.dumps(report))
                continue
            interrupts.check()
            report = _compute_one(args, job, mesh_io, several, warned, interrupts)
        except Exception as exc:  # noqa: BLE001 - each kind is mapped, the rest re-raised
            interrupts.check()  # a KeyboardInterrupt that a library turned into an error
            status, message = failure(exc)
            message = naming_a_file(job, message)
            _fail(message, status)
            first_failure = first_failure or status
            report = error_report(job, status, message, warned)
        if args.json:
            _say(json.dumps(report))
    return first_failure


def _compute_one(args, job, mesh_io, several, warned, interrupts) -> dict:
    """Read, compute and write one input; returns its --json object. Warnings are printed
    (one line each, naming the file) and appended to `warned`."""
    bar = None if args.quiet else (os.path.basename(job.source) if several else PROG)
    with _progress_bar(bar) as progress:
        report = run_job(
            job,
            compute_options(args),
            mesh_io,
            segment_options=segment_options(args),
            warn=lambda message: _warn(job, warned, message),
            progress=interrupts.checked(progress),
            check=interrupts.check,
        )
    report["warnings"] = list(warned)
    if not args.quiet and not args.json:
        _say_done(args, job, report)
    return report


def _say_done(args, job, report) -> None:
    parts = f", {report['segments']['count']} segments" if "segments" in report else ""
    _say(
        f"{job.source}: {report['point_count']} {args.points}, {args.rays} rays, "
        f"{_smoothing_words(args.smooth)}{parts}, {report['total_seconds']:.2f} s on "
        f"{report['engine']} -> {job.output}"
    )


def segment_options(args):
    """--segment's options as segment() keywords, or None without --segment."""
    if args.segment is None:
        return None
    given = {
        "clusters": args.segment,
        "smoothness": args.smoothness,
        "mode": args.segment_mode,
        "min_part_area": args.min_part_area,
        "segments": args.segments,
    }
    return {**SEGMENT_DEFAULTS, **{k: v for k, v in given.items() if v is not None}}


def _smoothing_words(method: str) -> str:
    """Which smoothing ran, for the line each input ends with."""
    return "no smoothing" if method == "none" else f"{method} smoothing"


def compute_options(args) -> dict:
    """The options as compute()'s keyword arguments (all of them but the mesh's and
    `progress`)."""
    return {
        "rays": args.rays,
        "cone_angle": args.cone,
        "sampling": args.sampling,
        "seed": args.seed,
        "points": args.points,
        "normalize": args.normalize,
        "orientation": args.orientation,
        "engine": args.engine,
        "accel": args.accel,
        "bvh_quality": args.bvh_quality,
        "threads": args.threads,
        "smoothing": args.smooth,
        "smoothing_options": _smoothing_options(args),
    }


def _warn(job, warned: list, message: str) -> None:
    """A warning about an input: one line on stderr naming its file, kept for --json."""
    message = _in_option_spelling(one_line(message))
    warned.append(message)
    print(f"{PROG}: warning: {naming_a_file(job, message)}", file=sys.stderr, flush=True)


def _skipped(args, job) -> dict:
    """--skip-existing: an input whose outputs exist; its --json object."""
    if not args.quiet and not args.json:
        _say(f"{job.source}: skipped, {job.output} exists")
    return skipped_report(job)


def _run_on_scheduler(args, jobs) -> int:
    """--scheduler: the planned inputs as tasks of a running Dask scheduler's workers; each
    input's lines and --json object printed as it arrives, as a run here prints them."""
    try:
        import distributed

        from . import distributed as on_dask
    except ImportError as exc:
        raise CommandError(
            f"--scheduler needs dask: pip install 'shape_diameter[distributed]' ({exc})",
            EXIT_ENVIRONMENT,
        ) from exc
    try:
        options = on_dask.task_options(compute_options(args), args.gpu)
    except ValueError as exc:
        raise CommandError(_in_option_spelling(str(exc)).replace("gpu=True", "--gpu")) from exc
    try:
        client = distributed.Client(args.scheduler, timeout=30)
    except (OSError, TimeoutError, ValueError) as exc:
        raise CommandError(
            f"--scheduler {args.scheduler}: cannot connect ({one_line(exc)})", EXIT_ENVIRONMENT
        ) from exc
    first_failure = 0

    def arrived(job, row):
        nonlocal first_failure
        row["warnings"] = [_in_option_spelling(message) for message in row["warnings"]]
        for message in row["warnings"]:
            print(f"{PROG}: warning: {naming_a_file(job, message)}", file=sys.stderr, flush=True)
        if row["status"] == "error":
            status = _fail(row["error"], row["exit_status"])
            first_failure = first_failure or status
        elif row["status"] == "skipped":
            _skipped(args, job)
        elif not args.quiet and not args.json:
            _say_done(args, job, row)
        if args.json:
            _say(json.dumps(row))
        bar.update()

    with client, _meshes_bar(None if args.quiet else len(jobs)) as bar:
        on_dask.run_jobs(
            client,
            jobs,
            options,
            gpu=args.gpu,
            skip_existing=args.skip_existing,
            segment=segment_options(args),
            on_result=arrived,
        )
    return first_failure


def _check_combinations(args) -> None:
    """An option that would do nothing beside the others is an error, as a smoothing flag of
    another method is: in a pipeline, a mistyped command should not pass silently. Fills in
    the defaults left as None to tell whether an option was given."""
    if args.seed is not None and args.sampling != "random":
        raise CommandError("--seed applies to --sampling random")
    if args.bvh_quality is not None and args.accel != "bvh":
        raise CommandError("--bvh-quality applies to --accel bvh")
    if args.output and args.output_dir is not None:
        raise CommandError("-o/--output names the output itself: leave out --output-dir")
    if args.gpu and args.scheduler is None:
        raise CommandError("--gpu applies to --scheduler (here, --engine picks the device)")
    if args.values and args.save_values:
        raise CommandError(
            "--values and --save-values both say where values go: give one "
            "(--values for one INPUT, --save-values for several)"
        )
    if args.segment is not None and args.points != "faces":
        raise CommandError("--segment needs --points faces (segments are made of faces)")
    for flag in ("smoothness", "segment_mode", "min_part_area", "segments"):
        if getattr(args, flag) is not None and args.segment is None:
            raise CommandError(f"--{flag.replace('_', '-')} applies to --segment")
    args.seed = 0 if args.seed is None else args.seed
    args.bvh_quality = args.bvh_quality or "auto"


def _refuse_unusable_engine(engine: str, here: bool = True) -> None:
    """The engine, before any input is read: a mistyped name is a bad option (status 2) and
    OpenCL missing on this machine is the machine's (status 1), said once, not as a failure of
    every input (a batch reported each asset as broken, status 2). Not `here`
    (--scheduler: the workers' devices count), the name only."""
    try:
        _check_engine(engine)
    except ValueError as exc:
        raise CommandError(_in_option_spelling(str(exc)), EXIT_USAGE) from exc
    if here and engine.startswith("opencl"):
        try:
            _core.opencl_select(engine)
        except ValueError as exc:
            status = EXIT_USAGE if _core.opencl_devices() else EXIT_ENVIRONMENT
            raise CommandError(f"--engine {engine}: {exc}", status) from exc


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


@contextlib.contextmanager
def _meshes_bar(total):
    """--scheduler's bar: meshes done of `total` (None: no bar), as _progress_bar shows its
    own (on a terminal, after half a second)."""
    bar = None
    if total is not None and sys.stderr.isatty():
        with contextlib.suppress(ImportError):
            from tqdm import tqdm

            bar = tqdm(total=total, delay=0.5, file=sys.stderr, leave=False, unit="mesh", desc=PROG)
    if bar is None:
        yield argparse.Namespace(update=lambda: None)
        return
    with bar:
        yield bar


@contextlib.contextmanager
def _progress_bar(label=PROG):
    """A progress callback for compute(): a tqdm bar on stderr labelled `label`, or a silent
    one (always with label None: --quiet).

    The bar only on a terminal (a bar in a log file is noise) and only after
    half a second, so quick runs print nothing. stdout is never touched. Always
    a callback: native code runs without Python, which takes Ctrl-C (SIGINT) only
    when the callback returns to it, so without one an interrupt would wait for
    the whole computation.
    """

    def silent(fraction: float) -> None:
        pass

    if label is None or not sys.stderr.isatty():
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
        desc=label,
    ) as bar:

        def update(fraction: float) -> None:
            percent = 100.0 * min(max(float(fraction), 0.0), 1.0)
            if percent > bar.n:
                bar.update(percent - bar.n)

        yield update


if __name__ == "__main__":
    sys.exit(console_main())
