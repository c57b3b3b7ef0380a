# SPDX-License-Identifier: GPL-3.0-or-later
"""The package's warnings, kept where the caller can read them: compute()'s in
Result.warnings, and everything inside collect_warnings() in the list it gives, without
Python's warnings module printing them.

warnings.catch_warnings cannot do this for a caller on a worker thread (the Blender add-on's,
a pipeline's thread pool): it swaps the process-wide filters, so two threads undo each other's.
Here what is kept lives in a context variable, which each thread has its own of."""

import contextlib
import contextvars
import functools
import warnings

# The active logs, innermost last: (messages, quiet, frames). quiet: not issued through the
# warnings module; frames: calls between the warning's caller and the frame its stacklevel
# counts from (compute()'s wrapper below).
_LOGS = contextvars.ContextVar("shape_diameter_warning_logs", default=())


def warn(message: str, stacklevel: int = 1) -> None:
    """A RuntimeWarning of the package: kept by every active log and, unless one of them is
    quiet, issued as warnings.warn would (stacklevel counted from the caller of warn)."""
    logs = _LOGS.get()
    for messages, _, _ in logs:
        messages.append(message)
    if any(quiet for _, quiet, _ in logs):
        return
    frames = sum(extra for _, _, extra in logs)
    warnings.warn(message, RuntimeWarning, stacklevel=stacklevel + 1 + frames)


@contextlib.contextmanager
def _logging(quiet: bool, frames: int):
    messages = []
    token = _LOGS.set(_LOGS.get() + ((messages, quiet, frames),))
    try:
        yield messages
    finally:
        _LOGS.reset(token)


def collect_warnings():
    """A context manager: the package's warnings raised inside, on this thread, go into the
    list it gives (their messages, in order) instead of being issued. Unlike
    warnings.catch_warnings, safe where other threads run the package too.

    >>> with shape_diameter.collect_warnings() as caught:
    ...     result = shape_diameter.compute(vertices, triangles)
    """
    return _logging(quiet=True, frames=0)


def recorded(function):
    """Decorates a function returning an object with a `warnings` attribute (compute()): the
    package's warnings raised during the call are kept there too, still issued as ever."""

    @functools.wraps(function)
    def call(*args, **kwargs):
        with _logging(quiet=False, frames=1) as messages:
            result = function(*args, **kwargs)
        result.warnings = messages
        return result

    return call
