# SPDX-License-Identifier: GPL-3.0-or-later
"""The command line's jobs: each input (folders expanded), the outputs it writes, and the
checks made before any work (paths that cannot be written, an output that is an input, two
inputs writing one file)."""

from __future__ import annotations

import contextlib
import fnmatch
import os

from .mesh_file_checks import READ_SUFFIXES

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


def default_output(input_path: str, folder=None, below="") -> str:
    """INPUT with its suffix replaced by .sdf.ply, in the same folder or in `folder` (in its
    subfolder `below`: where --recursive found it, under the input folder)."""
    stem = os.path.splitext(input_path)[0]
    if folder is not None:
        stem = os.path.join(folder, below, os.path.basename(stem))
    return stem + DEFAULT_SUFFIX


def _make_folder(folder: str) -> None:
    """--output-dir, made with its parents when missing."""
    try:
        os.makedirs(folder, exist_ok=True)
    except FileExistsError:
        raise CommandError(f"{folder}: --output-dir is a file, not a folder") from None
    except OSError as exc:
        raise CommandError(f"{folder}: cannot make the output folder ({exc.strerror})") from exc


def default_values(output_path: str) -> str:
    """--save-values: OUTPUT with its suffix replaced by .npy (cow.sdf.ply -> cow.sdf.npy)."""
    return os.path.splitext(output_path)[0] + ".npy"


class Job:
    """One input file and the outputs it writes; `problem` when it cannot even start (a
    folder without meshes); `done` when --skip-existing finds its outputs written."""

    def __init__(self, source: str, output=None, values=None, problem=None, done=False):
        self.source, self.output, self.values, self.problem = source, output, values, problem
        self.done = done


def plan(args, write_suffixes) -> list:
    """The inputs (folders expanded) and their outputs, checked before any work: paths that
    cannot be written, an output that is an input, two inputs writing one file."""
    sources, problems = [], {}
    below = {}  # a mesh --recursive found: its subfolder, under the folder given
    recursive = args.recursive
    for source in args.input:
        if os.path.isdir(source):
            try:
                found = _meshes_under(source, problems) if recursive else _meshes_in(source)
                for path in found:
                    subfolder = os.path.relpath(os.path.dirname(path), source)
                    below[path] = "" if subfolder == os.curdir else subfolder
            except OSError as exc:  # e.g. no permission to list it
                found, problems[source] = [], f"{source}: cannot list the folder ({exc.strerror})"
            sources += found
            if not found:
                where = (
                    "in the folder or its subfolders"
                    if recursive
                    else "in the folder (--recursive searches its subfolders)"
                )
                problems.setdefault(source, f"{source}: no mesh files {where} (looked for "
                                            f"{', '.join(READ_SUFFIXES)}; skipped *.sdf.*, the "
                                            "outputs of this command)")  # fmt: skip
                sources.append(source)
        else:
            sources.append(source)
    several = len(sources) > 1 or len(problems) > 0 or any(map(os.path.isdir, args.input))
    # ("there are 1 inputs" was said of a folder holding one mesh)
    what = f"there are {len(sources)} inputs" if len(sources) > 1 else "the input is a folder"
    if several and args.output:
        raise CommandError(
            f"-o/--output names one file, but {what}: leave it out to write each next to its "
            f"input (INPUT{DEFAULT_SUFFIX})"
        )
    if several and args.values:
        raise CommandError(
            f"--values names one file, but {what}: use --save-values to write each input's "
            "values next to its output (INPUT.sdf.npy)"
        )
    if args.output_dir is not None and any(source not in problems for source in sources):
        _make_folder(args.output_dir)  # (not for a run that found no mesh anywhere)
    jobs = []
    for source in sources:
        if source in problems:
            jobs.append(Job(source, problem=problems[source]))
            continue
        subfolder = below.get(source, "")
        if args.output_dir is not None and subfolder:
            folder = os.path.join(args.output_dir, subfolder)
            try:
                os.makedirs(folder, exist_ok=True)
            except OSError as exc:  # this input's failure: the others go on
                jobs.append(
                    Job(
                        source,
                        problem=f"{source}: cannot make its output folder "
                        f"{folder} ({exc.strerror})",
                    )
                )
                continue
        output = args.output or default_output(source, args.output_dir, subfolder)
        values = args.values or (default_values(output) if args.save_values else None)
        try:
            if args.output or os.path.exists(source):  # (a missing input fails on its own)
                _check_writable_path(output, write_suffixes)
            if args.values or (values and os.path.exists(source)):
                _check_writable_path(values, None)
            _check_distinct(source, output, values)
        except CommandError as exc:  # this input's failure: the others go on
            jobs.append(Job(source, problem=str(exc)))
            continue
        # Outputs are written whole or not at all, the mesh and its values together: files
        # that exist are a finished run's (or a user's: --skip-existing trusts them).
        # A missing input is not done: it fails as it would without the option (a mistyped
        # name beside an old output was "skipped", status 0).
        done = (
            args.skip_existing
            and os.path.exists(source)
            and all(os.path.exists(path) for path in (output, values) if path is not None)
        )
        jobs.append(Job(source, output, values, done=done))
    _check_no_collisions([job for job in jobs if job.problem is None])
    return jobs


def _meshes_under(folder: str, problems: dict) -> list:
    """The mesh files of a folder and of its subfolders (depth first, each folder's meshes
    before its subfolders', by name), as _meshes_in finds them; hidden subfolders are skipped,
    and links to folders are not followed (no loops). A subfolder that cannot be listed is
    in the list too, with its problem in `problems` (the rest of the tree goes on); the
    folder given raises OSError as _meshes_in does."""
    found = _meshes_in(folder)
    subfolders = sorted(entry.name for entry in os.scandir(folder)
                        if not entry.name.startswith(".")
                        and entry.is_dir(follow_symlinks=False))  # fmt: skip
    for name in subfolders:
        path = os.path.join(folder, name)
        try:
            found += _meshes_under(path, problems)
        except OSError as exc:  # e.g. no permission to list it
            problems[path] = f"{path}: cannot list the folder ({exc.strerror})"
            found.append(path)
    return found


def _meshes_in(folder: str) -> list:
    """The mesh files of a folder (not of its subfolders), by name; hidden files, the outputs
    of this command (*.sdf.*) and its temporary files are skipped."""
    found = []
    for entry in sorted(os.scandir(folder), key=lambda e: e.name):
        name = entry.name
        if (name.startswith(".") or fnmatch.fnmatch(name, "*.sdf.*")
                or os.path.splitext(name)[1].lower() not in READ_SUFFIXES):  # fmt: skip
            continue
        # Only folders are left out (--recursive walks them). What else bears a mesh's name
        # fails as an input of its own: a link to nothing or to itself (one vanished, one
        # stopped the whole folder), a FIFO or a socket (not skipped without a word).
        try:
            if entry.is_dir():
                continue
        except OSError:
            pass
        found.append(os.path.join(folder, name))
    return found


def _check_no_collisions(jobs) -> None:
    """Before any work: a second input writing a file that an earlier one writes (a.obj and
    a.ply both make a.sdf.ply) fails on its own, the others go on (one such pair in a folder
    of thousands stopped the whole batch); an input given twice, or one that
    another input's run would overwrite, refuses the run."""
    written = {}  # real path of an earlier input's output -> that input
    for job in jobs:
        for path in (job.output, job.values):
            if path is None:
                continue
            key = os.path.realpath(path)
            if key in written:
                if _same_file(written[key], job.source):
                    raise CommandError(f"{job.source}: is given twice")
                job.problem = (
                    f"{job.source}: would write {path}, which {written[key]} writes: "
                    "give them separate runs, or rename one"
                )
                break
        if job.problem is not None:
            continue
        for path in (job.output, job.values):
            if path is not None:
                written[os.path.realpath(path)] = job.source
    identities = {}  # each input: its real path and, where it exists, (device, inode)
    for job in jobs:
        identities[os.path.realpath(job.source)] = job.source
        with contextlib.suppress(OSError):
            status = os.stat(job.source)
            identities[(status.st_dev, status.st_ino)] = job.source
    for key, source in written.items():
        other = identities.get(key)
        if other is None:
            with contextlib.suppress(OSError):
                status = os.stat(key)
                other = identities.get((status.st_dev, status.st_ino))
        if other is not None and other != source:
            raise CommandError(
                f"{other} is an input, and {source}'s output: it would be overwritten; "
                "leave it out of the inputs (a folder input skips *.sdf.* files)"
            )


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
