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
import os
import sys
import warnings

# The active logs, innermost last: (messages, quiet). quiet: not issued through the warnings
# module.
_LOGS = contextvars.ContextVar("shape_diameter_warning_logs", default=())
_PACKAGE = os.path.dirname(os.path.abspath(__file__)) + os.sep


def warn(message: str) -> None:
    """A RuntimeWarning of the package: kept by every active log and, unless one of them is
    quiet, issued naming the line that called into the package (the first frame outside it:
    a count of frames went wrong where compute() ran inside another's progress callback)."""
    logs = _LOGS.get()
    for messages, _ in logs:
        messages.append(message)
    if any(quiet for _, quiet in logs):
        return
    level, frame = 2, sys._getframe(1)  # 2: warn's caller
    while frame is not None and os.path.abspath(frame.f_code.co_filename).startswith(_PACKAGE):
        level, frame = level + 1, frame.f_back
    warnings.warn(message, RuntimeWarning, stacklevel=level)


@contextlib.contextmanager
def _logging(quiet: bool):
    messages = []
    token = _LOGS.set(_LOGS.get() + ((messages, quiet),))
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
    return _logging(quiet=True)


def recorded(function):
    """Decorates a function returning an object with a `warnings` attribute (compute()): the
    package's warnings raised during the call are kept there too, still issued as ever."""

    @functools.wraps(function)
    def call(*args, **kwargs):
        with _logging(quiet=False) as messages:
            result = function(*args, **kwargs)
        result.warnings = messages
        return result

    return call
