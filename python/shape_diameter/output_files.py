# SPDX-License-Identifier: GPL-3.0-or-later
"""Output files written whole or not at all.

A write that fails half way (a full disk, a file size limit, Ctrl-C) once left a truncated
file in place of the output, and destroyed an earlier, good one. Each output is written to a
temporary file beside it (same folder, so same file system) and renamed over the output only
when complete: os.replace is atomic, so readers see the old file or the new one, never a part.
"""

from __future__ import annotations

import contextlib
import os
import secrets
import stat

# Temporary files are hidden and end in this, so a folder listing (and the command line's
# folder inputs) can tell them from meshes.
TEMPORARY_SUFFIX = ".part"


class WriteError(OSError):
    """A failed write, its message naming the file (and whether an old one was kept)."""


@contextlib.contextmanager
def written_whole(path):
    """Yield a temporary path to write `path`'s content into; on leaving without an
    exception, it replaces `path`. On any failure (an exception, KeyboardInterrupt included)
    the temporary file is removed, an existing `path` is left as it was, and an OSError is
    re-raised with a message naming `path`.

    A symbolic link at `path` is kept: the file it points to is replaced. The new file gets
    the permissions of the one it replaces, or the usual ones (0666 less the umask). A path
    that is a device or a pipe is written into directly (yielded as it is).
    """
    path = os.fspath(path)
    try:
        mode = os.stat(path).st_mode  # through links
    except OSError:
        mode = stat.S_IFREG  # not there (yet): made whole below
    if not stat.S_ISREG(mode) and not stat.S_ISDIR(mode):
        # A device or a pipe (--values /dev/null, a FIFO): written into, never replaced. Run
        # as root, a replace made /dev/null a plain file for the whole machine (and so
        # /dev/full). Opened by its own name: /dev/stdout on a pipe is a link to
        # /proc/self/fd/1, whose target, 'pipe:[N]', names no file.
        try:
            yield path
        except WriteError:  # another file's, written inside this one's (mesh and values)
            raise
        except OSError as exc:
            raise _named(path, exc) from exc
        return
    target = os.path.realpath(path) if os.path.islink(path) else path
    folder, name = os.path.split(os.path.abspath(target))
    try:
        temporary, descriptor = _create_beside(folder, name)
    except OSError as exc:
        raise _named(path, exc) from exc
    os.close(descriptor)
    try:
        yield temporary
        with contextlib.suppress(FileNotFoundError):  # keep a replaced file's permissions
            os.chmod(temporary, stat.S_IMODE(os.stat(target).st_mode))
        os.replace(temporary, target)
    except BaseException as exc:
        with contextlib.suppress(OSError):
            os.unlink(temporary)
        if isinstance(exc, OSError) and not isinstance(exc, WriteError):
            raise _named(path, exc) from exc
        raise


def _create_beside(folder: str, name: str):
    for _ in range(100):
        temporary = os.path.join(folder, f".{name}.{secrets.token_hex(4)}{TEMPORARY_SUFFIX}")
        try:
            return temporary, os.open(temporary, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
        except FileExistsError:
            continue
    raise FileExistsError(f"no free temporary name in {folder}")


def _named(path: str, exc: OSError) -> WriteError:
    reason = exc.strerror or str(exc) or type(exc).__name__
    kept = "the existing file is left as it was" if os.path.exists(path) else "nothing written"
    return WriteError(f"{path}: cannot write ({reason}); {kept}")
