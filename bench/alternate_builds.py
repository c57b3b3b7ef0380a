# SPDX-License-Identifier: GPL-3.0-or-later
"""Old build against new in one run, for the bench scripts that print one JSON line per
measurement (kring_stages.py, smoothing_stages.py): the script runs itself under each
PYTHONPATH in turn ("" for the installed package), alternating --rounds times, and keeps the
best row of each key and build. On a shared machine only a comparison made in one run means
anything."""

import json
import os
import subprocess
import sys
from pathlib import Path


def add_arguments(parser, rounds):
    parser.add_argument("--compare", nargs=2, metavar=("OLD_PYTHONPATH", "NEW_PYTHONPATH"))
    parser.add_argument("--rounds", type=int, default=rounds, help="with --compare: alternations")


def without_compare(argv):
    """The command line minus --compare and its two paths: what each build's run is given."""
    argv = list(argv)
    i = argv.index("--compare")
    del argv[i : i + 3]
    return argv


def best_rows(script, args, key, merge):
    """{key(row) + (label,): row} for labels 'old' and 'new', merge(best, row) keeping the
    better of two rows of one key."""
    versions = {"old": args.compare[0], "new": args.compare[1]}
    argv = without_compare(sys.argv[1:])
    best = {}
    for _ in range(args.rounds):
        for label, path in versions.items():
            env = dict(os.environ, PYTHONPATH=str(Path(path).resolve()) if path else "")
            out = subprocess.run([sys.executable, script, *argv], env=env, check=True,
                                 capture_output=True, text=True).stdout  # fmt: skip
            for line in out.splitlines():
                row = json.loads(line)
                k = key(row) + (label,)
                best[k] = merge(best[k], row) if k in best else row
    return best
