# SPDX-License-Identifier: GPL-3.0-or-later
"""The ``shape-diameter`` console script's entry point.

It lives outside the ``shape_diameter`` package so that it runs before the package's imports
(numpy and the native core; then trimesh, about 0.5-0.9 s in all): SIGINT arriving during
those is only recorded here, and the command acts on it once it can, printing its one-line
message and dying by SIGINT so that a shell stops its loop. Without it, Ctrl-C in the first
0.2 s printed a traceback, and in the next 0.25 s trimesh's imports (``except
BaseException``) swallowed it and the run went on.
"""

# The C module under `signal`: importing `signal` itself imports enum, a few milliseconds
# during which Ctrl-C still meets Python's own handler (a traceback).
try:
    import _signal as signal
except ImportError:  # another Python than CPython
    import signal


def main():
    pending = []  # the SIGINTs received, handed to the command

    def record(signum, frame):
        pending.append(signum)

    try:
        signal.signal(signal.SIGINT, record)
    except (ValueError, OSError):  # not the main thread: signals are not ours to take
        pending = None
    from shape_diameter.cli import console_main

    return console_main(pending)
