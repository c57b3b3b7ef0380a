# SPDX-License-Identifier: GPL-3.0-or-later
"""Ctrl-C on the command line: at any moment, one line on stderr, no output file, and death by
SIGINT, so that a shell running the command in a loop stops (an exit status of 130 did not:
bash went on with the next file)."""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

pytest.importorskip("trimesh")

DATA = Path(__file__).resolve().parents[1] / "data"
SCRIPT = Path(sys.executable).with_name("shape-diameter")  # the console script, as installed
# A run of 10-30 s on the 2-core development machine: every SIGINT below comes during it.
LONG = ["--engine", "cpu", "--smooth", "texture", "--texture-size", "8192"]
INTERRUPTED = "shape-diameter: error: interrupted\n"


def _interrupt(command, delay, **options):
    run = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                           **options)  # fmt: skip
    time.sleep(delay)
    if options.get("start_new_session"):
        os.killpg(run.pid, signal.SIGINT)  # as a terminal does: the whole foreground group
    else:
        run.send_signal(signal.SIGINT)
    out, err = run.communicate(timeout=60)
    return run.returncode, out, _without_the_long_work_notice(err)


def _without_the_long_work_notice(err):
    """LONG is announced as long texture work before it starts: that line is expected."""
    return "".join(
        line
        for line in err.splitlines(keepends=True)
        if "texture smoothing at 8192 x 8192 texels: about" not in line
    )


# 0.1-0.2 s: numpy and the native core being imported (a traceback once); 0.25-0.45 s:
# trimesh being imported, which caught the KeyboardInterrupt (the run completed, status 0);
# then reading the mesh, and computing.
@pytest.mark.parametrize("delay", [0.1, 0.2, 0.3, 0.4, 0.5, 0.7, 1.0, 2.0])
def test_ctrl_c_at_any_moment_stops_the_run_by_sigint(tmp_path, delay):
    assert SCRIPT.is_file(), "the package is installed with its console script"
    output = tmp_path / "out.ply"
    status, out, err = _interrupt([SCRIPT, DATA / "spot.obj", "-o", output, *LONG], delay)
    assert (status, out, err) == (-signal.SIGINT, "", INTERRUPTED)
    assert list(tmp_path.iterdir()) == []  # no output, no temporary file


def test_python_dash_m_stops_by_sigint_too(tmp_path):
    command = [sys.executable, "-m", "shape_diameter", DATA / "spot.obj", "-o",
               tmp_path / "out.ply", *LONG]  # fmt: skip
    assert _interrupt(command, 1.0) == (-signal.SIGINT, "", INTERRUPTED)
    assert list(tmp_path.iterdir()) == []


def test_ctrl_c_stops_a_shell_loop(tmp_path):
    # for f in ...; do shape-diameter "$f"; done: bash ends the loop only when its command
    # died by SIGINT.
    loop = (
        f'for f in 1 2 3; do "{SCRIPT}" "{DATA / "spot.obj"}" -o "{tmp_path}/out$f.ply" '
        f'{" ".join(LONG)}; echo "after $f: $?"; done; echo "loop done"'
    )
    status, out, err = _interrupt(["bash", "-c", loop], 1.5, start_new_session=True)
    assert (status, out, err) == (-signal.SIGINT, "", INTERRUPTED)
    assert list(tmp_path.iterdir()) == []


def test_ctrl_c_stops_every_input_of_a_batch(tmp_path):
    inputs = []
    for name in ("a", "b", "c"):
        inputs.append(tmp_path / f"{name}.obj")
        inputs[-1].write_bytes((DATA / "spot.obj").read_bytes())
    status, out, err = _interrupt([SCRIPT, *inputs, "--json", *LONG], 1.5)
    assert (status, out, err) == (-signal.SIGINT, "", INTERRUPTED)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.obj", "b.obj", "c.obj"]


def _run_python(code, tmp_path):
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=False, timeout=120, cwd=tmp_path)  # fmt: skip


def test_a_ctrl_c_held_during_the_imports_stops_the_run_before_it_starts(tmp_path):
    # The entry point only records SIGINT while modules are imported; the command acts on it
    # as soon as its own imports are done, before reading anything.
    code = (
        "import sys\n"
        "from shape_diameter import cli\n"
        f"sys.argv = ['shape-diameter', {str(DATA / 'spot.obj')!r}, '-o', 'out.ply']\n"
        "cli.console_main([2])\n"
        "print('not reached')\n"
    )
    done = _run_python(code, tmp_path)
    assert (done.returncode, done.stdout, done.stderr) == (-signal.SIGINT, "", INTERRUPTED)
    assert list(tmp_path.iterdir()) == []


def test_a_ctrl_c_that_a_library_swallows_still_stops_the_run(tmp_path):
    # trimesh catches BaseException in places: a KeyboardInterrupt raised there is lost, but
    # the SIGINT was recorded, and the next check point stops the run.
    code = (
        "import os, signal, sys\n"
        "from shape_diameter import cli, mesh_io\n"
        "real = mesh_io.load_mesh\n"
        "def swallowing(path):\n"
        "    try:\n"
        "        os.kill(os.getpid(), signal.SIGINT)\n"
        "        sum(range(100000))  # the handler runs, and raises, in here\n"
        "    except BaseException:\n"
        "        pass\n"
        "    return real(path)\n"
        "mesh_io.load_mesh = swallowing\n"
        f"sys.argv = ['shape-diameter', {str(DATA / 'spot.obj')!r}, '-o', 'out.ply']\n"
        "cli.console_main([])\n"
    )
    done = _run_python(code, tmp_path)
    assert (done.returncode, done.stdout, done.stderr) == (-signal.SIGINT, "", INTERRUPTED)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGHUP])
def test_sigterm_and_sighup_stop_the_run_as_ctrl_c_does(tmp_path, signum):
    # `timeout`, batch schedulers and a closed terminal send these: they left hidden
    # temporary files behind, and said nothing.
    output = tmp_path / "out.ply"
    run = subprocess.Popen(
        [SCRIPT, DATA / "spot.obj", "-o", output, *LONG],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    time.sleep(1.5)
    run.send_signal(signum)
    out, err = run.communicate(timeout=60)
    assert (run.returncode, out, _without_the_long_work_notice(err)) == (-signum, "", INTERRUPTED)
    assert list(tmp_path.iterdir()) == []


def test_a_closed_standard_output_stops_the_run_quietly(tmp_path):
    # shape-diameter FOLDER --json | head -c1: a traceback (--json), or every later input
    # reported as failed (without).
    for name in ("a", "b"):  # the second's line comes after the reader is gone
        (tmp_path / f"{name}.obj").write_bytes((DATA / "spot.obj").read_bytes())
    for extra in (["--json"], []):
        run = subprocess.Popen(
            [SCRIPT, tmp_path, "--engine", "cpu", "--rays", "512", *extra],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
        )
        run.stdout.read(1)
        run.stdout.close()
        err = run.stderr.read().decode()
        run.stderr.close()
        assert run.wait(timeout=60) == 141 and err == "", (extra, err)
