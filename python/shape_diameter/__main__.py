# SPDX-License-Identifier: GPL-3.0-or-later
"""`python -m shape_diameter`: the command line (the `shape-diameter` script)."""

import sys

from .cli import console_main

sys.exit(console_main())
