# SPDX-License-Identifier: GPL-3.0-or-later
"""Where the work runs: the engines found here, the check of an `engine=` argument and what
'auto' picks (its fallback from a failed OpenCL device to the CPU is the core's:
pipeline/fallback.h). compute() and smooth() share these rules."""

from __future__ import annotations

import os

from . import _core
from .warning_log import warn


def engines() -> list:
    """The engines that can run here. Each is a dict with 'name' (what `engine=` takes),
    'type' ('CPU' or 'GPU') and 'description'; OpenCL devices add 'device', 'platform',
    'driver', 'memory' (bytes), 'compute_units' and 'double' (double precision: texture
    smoothing runs on a device only with it), among others ('threads' on "cpu"; 'index',
    'vendor', 'version', 'max_allocation', 'clock_mhz' on devices). "cpu" is always there;
    OpenCL devices are listed when an OpenCL driver is installed (none is needed otherwise)."""
    threads = _core.hardware_threads()
    found = [
        {
            "name": "cpu",
            "type": "CPU",
            "threads": threads,
            "description": f"{threads} thread{'s' if threads != 1 else ''}",
        }
    ]
    for d in _core.opencl_devices():
        entry = dict(d)
        entry["name"] = f"opencl:{d['index']}"
        entry["description"] = f"{d['device']} ({d['platform']}, {d['memory'] >> 20} MiB)"
        found.append(entry)
    return found


def check_engine(engine):
    if not isinstance(engine, str) or not (
        engine in ("auto", "cpu") or engine == "opencl" or engine.startswith("opencl:")
    ):
        names = ", ".join(["auto"] + [e["name"] for e in engines()])
        raise ValueError(
            f"unknown engine {engine!r}; available here: {names} (also 'opencl' for the best "
            "OpenCL device, 'opencl:all' for every GPU (every OpenCL device where there is no "
            "GPU), 'opencl:<part of a device name>')"
        )


def resolve_engine(engine: str) -> str:
    """'auto' is the best OpenCL GPU when there is one, else the CPU engine (on a CPU, the
    native engine outruns OpenCL on PoCL)."""
    if engine != "auto":
        return engine
    if any(d["type"] == "GPU" for d in _core.opencl_devices()):
        return "opencl"
    if _core.opencl_gpu_lost_to_fork():  # a fork-started worker: its OpenCL calls hang
        warn(f"engine='auto' runs on the CPU: {_core.opencl_unavailable_reason()}")
    return "cpu"


# The OpenCL engine's own errors, including a device too small for the work: what
# engine='auto' runs past on the CPU, and what a batch reports as the device's fault.
DEVICE_ERRORS = (_core.OpenCLError,) if hasattr(_core, "OpenCLError") else ()


_PROGRAM_CACHES_CHECKED = set()


def unwritable_program_cache():
    """The OpenCL program cache's folder the first time this process finds it cannot be made
    or written, else None: the core then compiles in every process without a word (about 9 s a
    run on PoCL). Each folder is checked once a process, so said once (a batch
    said it for every input)."""
    folder = _core.opencl_cache_directory()
    if not folder or folder in _PROGRAM_CACHES_CHECKED:
        return None
    _PROGRAM_CACHES_CHECKED.add(folder)
    try:
        os.makedirs(folder, exist_ok=True)
    except OSError:
        return folder
    return None if os.access(folder, os.W_OK) else folder
