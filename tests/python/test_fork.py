# SPDX-License-Identifier: GPL-3.0-or-later
"""Worker processes forked after the parent used OpenCL (multiprocessing's default start
method on Linux): OpenCL calls there hung for ever (a Pool's workers). Now such a process lists
no OpenCL device, 'auto' runs on the CPU (with a warning where the parent had a GPU) and an
explicit OpenCL engine is refused, saying why."""

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
from opencl_devices import OPENCL

SPOT = Path(__file__).resolve().parents[1] / "data" / "spot.obj"

SCRIPT = textwrap.dedent("""
    import json, multiprocessing, sys, warnings
    import shape_diameter as sd

    V, F = sd.load_mesh(sys.argv[1])
    DEVICE = sys.argv[2]

    def work(engine):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            try:
                result = sd.compute(V, F, engine=engine, rays=4)
                outcome = [float(result.raw.sum()), result.engine]
            except ValueError as exc:
                outcome = ["ValueError", str(exc)]
        return outcome, [str(w.message) for w in caught], [e["name"] for e in sd.engines()]

    if __name__ == "__main__":
        parent = sd.compute(V, F, engine=DEVICE, rays=4)  # the parent uses OpenCL
        gpu = any(e["type"] == "GPU" for e in sd.engines())
        with multiprocessing.get_context("fork").Pool(1) as pool:
            done = pool.map_async(work, ["auto", DEVICE, "cpu"]).get(timeout=120)
        print(json.dumps({"parent": float(parent.raw.sum()), "gpu": gpu, "done": done}))
""")


def test_a_forked_worker_runs_on_the_cpu_and_refuses_opencl_instead_of_hanging(tmp_path):
    script = tmp_path / "fork_after_opencl.py"
    script.write_text(SCRIPT)
    run = subprocess.run(
        [sys.executable, "-W", "ignore::DeprecationWarning", str(script), str(SPOT), OPENCL[0]],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert run.returncode == 0, run.stderr
    report = json.loads(run.stdout.splitlines()[-1])
    (auto, auto_warnings, listed), (device, _, _), (cpu, _, _) = report["done"]
    assert listed == ["cpu"]  # the parent's devices are not offered
    assert auto[1].startswith("cpu") and cpu[1].startswith("cpu")
    assert auto[0] == cpu[0]
    assert abs(auto[0] - report["parent"]) <= 1e-4 * abs(report["parent"])  # same rule
    assert device[0] == "ValueError"
    assert "cannot be used in a process forked from one that had used it" in device[1]
    assert "'spawn'" in device[1]
    if report["gpu"]:  # 'auto' would have taken the GPU: it says why it did not
        assert any("engine='auto' runs on the CPU" in w for w in auto_warnings), auto_warnings
    else:
        assert auto_warnings == []


@pytest.mark.skipif(not hasattr(os, "sched_setaffinity"), reason="Linux affinity only")
def test_every_core_means_the_cores_the_process_may_use():
    # A farm slot pinned to one core (taskset, a cpuset) ran a thread per core of
    # the machine. threads=0 now takes the process's affinity.
    code = (
        "import shape_diameter as sd, shapes; "
        "print(sd.engines()[0]['threads'], "
        "sd.compute(*shapes.icosphere(1.0, 1), engine='cpu').engine)"
    )
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=True,
        preexec_fn=lambda: os.sched_setaffinity(0, {min(os.sched_getaffinity(0))}),
        env={**os.environ, "PYTHONPATH": os.pathsep.join(
            [os.path.dirname(__file__), *filter(None, [os.environ.get("PYTHONPATH")])])},
    )  # fmt: skip
    assert done.stdout.split()[:3] == ["1", "cpu", "(1"], done.stdout


@pytest.mark.skipif(not hasattr(os, "sched_setaffinity"), reason="Linux affinity only")
def test_a_forked_worker_pinned_by_its_initializer_takes_its_own_cores():
    # A review's: the count was read once a process, so a Pool worker forked after the
    # parent's first use and pinned by its initializer still ran a thread per parent core.
    code = textwrap.dedent("""
        import multiprocessing, os, shape_diameter as sd
        sd.engines()  # the parent's first use
        def pin():
            os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
        def threads(_):
            return sd.engines()[0]["threads"]
        with multiprocessing.get_context("fork").Pool(1, initializer=pin) as pool:
            print(pool.map(threads, [0])[0])
    """)
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=True
    )
    assert done.stdout.split() == ["1"], done
