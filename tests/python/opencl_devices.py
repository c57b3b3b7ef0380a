# SPDX-License-Identifier: GPL-3.0-or-later
"""The OpenCL devices the OpenCL test files run on: GPUs first, so that on a machine with one
the tests exercise it (PoCL is the CPU fallback). No device fails the importing test file:
CI installs PoCL (scripts/setup.sh), so none there is a failure, not a skip."""

import pytest
import shape_diameter as sd
from shape_diameter import _core

OPENCL = [
    e["name"]
    for e in sorted(sd.engines(), key=lambda e: e["type"] != "GPU")
    if e["name"].startswith("opencl")
]

if not OPENCL:
    pytest.fail(
        f"no OpenCL device found ({_core.opencl_unavailable_reason()}); install pocl-opencl-icd",
        pytrace=False,
    )
