# SPDX-License-Identifier: GPL-3.0-or-later
from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("shape_diameter")
except PackageNotFoundError:  # running from a source tree
    __version__ = "0.0.0"
