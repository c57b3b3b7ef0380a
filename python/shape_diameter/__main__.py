# SPDX-License-Identifier: GPL-3.0-or-later
"""`python -m shape_diameter`: the command line (the `shape-diameter` script)."""

import sys

from .cli import main

sys.exit(main())
