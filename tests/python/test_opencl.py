# SPDX-License-Identifier: GPL-3.0-or-later
"""The OpenCL engine on PoCL (CPU OpenCL): same answers as the CPU engine, its device
selection, its errors, its program cache, and life without any OpenCL at all."""

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import shape_diameter as sd
from opencl_devices import OPENCL
from shape_diameter import _core, _testing
from shape_diameter.mesh_io import load_mesh

DATA = Path(__file__).resolve().parents[1] / "data"
MESHES = sorted(p.name for p in DATA.iterdir() if p.suffix in (".obj", ".off", ".ply"))


def run_python(code, **env):
    """Runs code in a fresh interpreter (a fresh process: no loaded library, no cached state)
    and returns its stdout parsed as JSON."""
    full_env = {**os.environ, **{k: str(v) for k, v in env.items()}}
    done = subprocess.run(
        [sys.executable, "-c", code], env=full_env, capture_output=True, text=True, timeout=300
    )
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout.strip().splitlines()[-1])


def agreement(a, b):
    """Points whose raw values differ by more than 1e-4 relative or whose valid-ray counts
    differ, and the worst of them (index, values, counts)."""
    rel = np.abs(a.raw - b.raw) / np.maximum(np.abs(b.raw), 1e-30)
    bad = (rel > 1e-4) | (a.valid_rays != b.valid_rays)
    worst = np.argsort(-rel)[:5]
    return bad, [
        (int(i), float(a.raw[i]), float(b.raw[i]), int(a.valid_rays[i]), int(b.valid_rays[i]))
        for i in worst
        if bad[i]
    ]


@pytest.fixture(scope="module", params=MESHES)
def mesh_and_cpu(request):
    vertices, triangles = load_mesh(DATA / request.param)
    return request.param, vertices, triangles, sd.compute(vertices, triangles, engine="cpu")


@pytest.mark.parametrize("accel", ["bvh", "octree"])
def test_opencl_matches_cpu_engine(mesh_and_cpu, accel):
    name, vertices, triangles, cpu = mesh_and_cpu
    cl = sd.compute(vertices, triangles, engine=OPENCL[0], accel=accel)
    assert cl.engine.startswith(OPENCL[0]) and f"({accel})" in cl.engine
    bad, worst = agreement(cl, cpu)
    # A ray grazing an edge may flip between two triangles on float rounding differences
    # (device sin/cos, fused multiply-adds): at most 0.1% of points may differ.
    assert bad.mean() <= 1e-3, f"{name}: {bad.sum()} of {bad.size} points differ; worst {worst}"
    assert np.isfinite(cl.raw).all()


@pytest.mark.parametrize("sampling", ["fibonacci", "cgal"])
@pytest.mark.parametrize("mesh", ["fandisk.obj", "teapot.obj"])
def test_deterministic_samplings_give_the_cpu_engines_bits(mesh, sampling):
    # Same ray table, no fused multiply-adds, correctly rounded division and square root: the
    # device computes every ray to the same bits as the CPU engine.
    vertices, triangles = load_mesh(DATA / mesh)
    cpu = sd.compute(vertices, triangles, engine="cpu", sampling=sampling)
    cl = sd.compute(vertices, triangles, engine=OPENCL[0], sampling=sampling)
    differ = np.flatnonzero(cl.raw != cpu.raw)
    assert differ.size == 0, f"{differ.size} points differ, first {differ[:5]}"
    np.testing.assert_array_equal(cl.valid_rays, cpu.valid_rays)


# Each device runs one cast kernel by default (GPUs: binary BVH, one work item per ray; CPU
# devices: 8-wide BVH, one per point); a test override forces each, so every kernel is
# checked on whatever device this machine has.
CAST_KERNELS = ["bvh_per_point", "bvh4_per_point", "bvh8_per_point", "bvh_per_ray"]


@pytest.mark.parametrize("kernel", CAST_KERNELS)
@pytest.mark.parametrize("sampling", ["fibonacci", "cgal", "random"])
@pytest.mark.parametrize("bvh_quality", ["high", "fast"])
def test_every_cast_kernel_gives_the_cpu_engines_bits(kernel, sampling, bvh_quality):
    vertices, triangles = load_mesh(DATA / "fandisk.obj")
    # 37 rays: groups of the per-ray kernel are not a multiple of a warp; vertices: some
    # points sit on creases where rays graze edges. The CPU engine casts the SAH tree, the
    # device either tree: every tree gives the nearest hit.
    options = dict(sampling=sampling, rays=37, points="vertices", seed=5)
    cpu = sd.compute(vertices, triangles, engine="cpu", bvh_quality="high", **options)
    with _testing.overrides(opencl_kernel=kernel):
        cl = sd.compute(vertices, triangles, engine=OPENCL[0], bvh_quality=bvh_quality, **options)
    np.testing.assert_array_equal(cl.valid_rays, cpu.valid_rays)
    if sampling == "random":  # the device's own sin and cos make the directions
        bad, worst = agreement(cl, cpu)
        assert bad.mean() <= 1e-3, worst
    else:
        differ = np.flatnonzero(cl.raw != cpu.raw)
        assert differ.size == 0, f"{kernel}: {differ.size} points differ, first {differ[:5]}"


@pytest.mark.parametrize("engine", ["cpu", OPENCL[-1]])
def test_the_fallback_for_cpus_without_avx2_gives_the_same_bits(engine):
    # A test override acts out such a CPU: the CPU engine then casts the 4-wide SSE tree and
    # CPU OpenCL devices the 4-wide kernel; the values must not change.
    vertices, triangles = load_mesh(DATA / "fandisk.obj")
    wide = sd.compute(vertices, triangles, engine=engine, rays=25)
    with _testing.overrides(cpu_without_avx2=True):
        narrow = sd.compute(vertices, triangles, engine=engine, rays=25)
    differ = np.flatnonzero(wide.raw != narrow.raw)
    assert differ.size == 0, f"{differ.size} points differ, first {differ[:5]}"
    np.testing.assert_array_equal(wide.valid_rays, narrow.valid_rays)


def test_an_unknown_cast_kernel_name_is_refused():
    with pytest.raises(ValueError, match="opencl_kernel='bvh8': use engine, bvh_per_point"):
        _testing.overrides(opencl_kernel="bvh8")
    assert _testing.current_overrides()["opencl_kernel"] == "engine"  # nothing was set


def test_octree_matches_bvh_on_the_cpu_engine(mesh_and_cpu):
    name, vertices, triangles, cpu = mesh_and_cpu
    octree = sd.compute(vertices, triangles, engine="cpu", accel="octree", octree_depth=8)
    bad, worst = agreement(octree, cpu)
    assert bad.mean() <= 1e-3, f"{name}: worst {worst}"


@pytest.mark.parametrize("sampling", ["random", "cgal"])
@pytest.mark.parametrize("points", ["faces", "vertices"])
def test_opencl_matches_cpu_for_every_sampling_and_point_kind(sampling, points):
    vertices, triangles = load_mesh(DATA / "spot.obj")
    options = dict(sampling=sampling, points=points, seed=3, rays=17, cone_angle=90.0)
    cpu = sd.compute(vertices, triangles, engine="cpu", **options)
    cl = sd.compute(vertices, triangles, engine=OPENCL[0], **options)
    bad, worst = agreement(cl, cpu)
    assert bad.mean() <= 1e-3, worst


def test_shared_struct_layouts_match_the_kernels():
    assert _testing.opencl_layout(0) == _testing.host_layout()


def test_engines_lists_opencl_devices_with_their_details():
    device = next(e for e in sd.engines() if e["name"] == "opencl:0")
    assert device["type"] in ("CPU", "GPU")
    assert device["memory"] > 0 and device["compute_units"] > 0
    assert device["platform"] and device["device"]


def test_device_selection_by_number_name_and_best():
    vertices, triangles = load_mesh(DATA / "cow.obj")
    best_device = sorted(sd.engines()[1:], key=lambda e: e["type"] != "GPU")[0]
    # A part of the best device's name, in another case: matching ignores case.
    name_part = best_device["device"].split()[0][:6].swapcase()
    by_name = sd.compute(vertices, triangles, engine=f"opencl:{name_part}")
    by_number = sd.compute(vertices, triangles, engine=best_device["name"])
    best = sd.compute(vertices, triangles, engine="opencl")
    np.testing.assert_array_equal(by_number.raw, best.raw)
    assert by_name.engine.startswith("opencl:") and best.engine.startswith("opencl:")
    np.testing.assert_array_equal(by_name.raw, best.raw)


@pytest.mark.parametrize("engine", ["opencl:99", "opencl:no-such-device", "opencl:", "vulkan"])
def test_a_bad_device_gives_a_clear_error(engine):
    vertices, triangles = load_mesh(DATA / "cow.obj")
    with pytest.raises(ValueError, match="device|engine") as error:
        sd.compute(vertices, triangles, engine=engine)
    assert "opencl:0" in str(error.value) or "auto" in str(error.value)


def test_a_kernel_that_does_not_compile_reports_its_build_log():
    broken = "__kernel void broken(__global float* x) { x[0] = undefined_name + ; }"
    with pytest.raises(RuntimeError) as error:
        _testing.opencl_build_source(0, broken)
    message = str(error.value)
    assert "clBuildProgram" in message and "CL_BUILD_PROGRAM_FAILURE" in message
    assert "undefined_name" in message or "expected expression" in message  # the log itself


def test_a_mesh_too_large_for_the_device_is_refused_before_allocating():
    code = (
        "import json, shape_diameter as sd\n"
        "from shape_diameter.mesh_io import load_mesh\n"
        f"v, t = load_mesh({str(DATA / 'bunny00.off')!r})\n"
        "try:\n"
        "    sd.compute(v, t, engine='opencl:0')\n"
        "    print(json.dumps('no error'))\n"
        "except RuntimeError as e:\n"
        "    print(json.dumps(str(e)))\n"
    )
    message = run_python(code, SDF_OPENCL_MAX_MEMORY=1 << 20)
    assert "does not fit" in message and "engine='cpu'" in message
    assert "the device has 1048576 bytes" in message  # small sizes in bytes, not rounded


@pytest.mark.parametrize("cap", ["1e9", "2G", "abc", "-5", " 100", "99999999999999999999999"])
def test_a_memory_cap_that_is_not_a_count_of_bytes_is_refused(cap):
    # strtoull alone read "1e9" as 1 byte, "2G" as 2, "abc" as 0 and "-5" as no cap at all.
    # OpenCL is then unavailable, saying why; the CPU engine and engine='auto' still work.
    code = (
        "import json, shape_diameter as sd\n"
        "v = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]\n"
        "t = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]\n"
        "auto = sd.compute(v, t).engine\n"
        "names = [e['name'] for e in sd.engines()]\n"
        "try:\n"
        "    sd.compute(v, t, engine='opencl:0')\n"
        "    error = 'no error'\n"
        "except ValueError as e:\n"
        "    error = str(e)\n"
        "print(json.dumps([auto, names, error]))\n"
    )
    auto, names, error = run_python(code, SDF_OPENCL_MAX_MEMORY=cap)
    assert auto.startswith("cpu (") and names == ["cpu"]
    assert f"SDF_OPENCL_MAX_MEMORY='{cap}'" in error and "digits only" in error


def test_program_cache_skips_the_compiler_and_rebuilds_a_corrupt_entry(tmp_path):
    code = (
        "import json, shape_diameter as sd\n"
        "from shape_diameter import _testing\n"
        "from shape_diameter.mesh_io import load_mesh\n"
        f"v, t = load_mesh({str(DATA / 'cow.obj')!r})\n"
        "r = sd.compute(v, t, engine='opencl:0')\n"
        "print(json.dumps(_testing.opencl_program_stats()))\n"
    )
    cache = tmp_path / "cache"
    first = run_python(code, SDF_CACHE_DIR=cache)
    assert first == {"compiled": 1, "from_cache": 0}
    files = list((cache / "opencl").glob("*.bin"))
    assert len(files) == 1
    second = run_python(code, SDF_CACHE_DIR=cache)
    assert second == {"compiled": 0, "from_cache": 1}
    # Corrupt the binary's body: the checksum catches it and the program is built again.
    data = bytearray(files[0].read_bytes())
    data[len(data) // 2] ^= 0xFF
    files[0].write_bytes(bytes(data))
    third = run_python(code, SDF_CACHE_DIR=cache)
    assert third == {"compiled": 1, "from_cache": 0}
    # Truncated, too: rebuilt, and the rewritten file is good again.
    files[0].write_bytes(files[0].read_bytes()[:20])
    assert run_python(code, SDF_CACHE_DIR=cache) == {"compiled": 1, "from_cache": 0}
    assert run_python(code, SDF_CACHE_DIR=cache) == {"compiled": 0, "from_cache": 1}


def test_a_program_cache_that_cannot_be_written_is_warned_of(tmp_path):
    # Every run compiled again (about 9 s on PoCL) without a word. Said once a
    # process (a batch said it for every input).
    (tmp_path / "file").write_text("")
    code = (
        "import json, warnings, shape_diameter as sd, shapes\n"
        "with warnings.catch_warnings(record=True) as caught:\n"
        "    warnings.simplefilter('always')\n"
        "    sd.compute(*shapes.icosphere(1.0, 1), engine='opencl:0', rays=3)\n"
        "    sd.compute(*shapes.icosphere(1.0, 1), engine='opencl:0', rays=3)\n"
        "    sd.compute(*shapes.icosphere(1.0, 1), engine='cpu', rays=3)\n"
        "print(json.dumps([str(w.message) for w in caught]))\n"
    )
    path = os.pathsep.join(
        [str(Path(__file__).parent), *filter(None, [os.environ.get("PYTHONPATH")])]
    )
    said = run_python(code, SDF_CACHE_DIR=tmp_path / "file" / "cache", PYTHONPATH=path)
    assert len(said) == 1 and "cannot be written: each process compiles" in said[0], said
    assert said[0].startswith(f"the OpenCL program cache {tmp_path / 'file' / 'cache'}")


def test_works_without_any_opencl_library():
    code = (
        "import json, numpy as np, shape_diameter as sd\n"
        "from shape_diameter.mesh_io import load_mesh\n"
        f"v, t = load_mesh({str(DATA / 'cow.obj')!r})\n"
        "r = sd.compute(v, t)\n"
        "try:\n"
        "    sd.compute(v, t, engine='opencl')\n"
        "    err = None\n"
        "except ValueError as e:\n"
        "    err = str(e)\n"
        "print(json.dumps({'engines': [e['name'] for e in sd.engines()], 'engine': r.engine,\n"
        "                  'finite': bool(np.isfinite(r.raw).all()), 'error': err}))\n"
    )
    out = run_python(code, SDF_OPENCL_LIBRARY="/nonexistent/libOpenCL.so.1")
    assert out["engines"] == ["cpu"]
    assert out["engine"].startswith("cpu") and out["finite"]
    assert "OpenCL is not available" in out["error"] and "no OpenCL library" in out["error"]


def test_the_module_does_not_link_libopencl():
    done = subprocess.run(["ldd", _core.__file__], capture_output=True, text=True, check=True)
    assert "libOpenCL" not in done.stdout


def test_opencl_all_shares_points_over_devices_with_identical_results():
    # POCL_DEVICES makes PoCL offer two CPU devices: the points are shared out between them.
    # Every fifth face reversed: the tree the devices share is built beside orientation and
    # its records rewritten after it.
    code = (
        "import json, numpy as np, shape_diameter as sd\n"
        "from shape_diameter.mesh_io import load_mesh\n"
        f"v, t = load_mesh({str(DATA / 'fandisk.obj')!r})\n"
        "t = t.copy(); t[::5] = t[::5][:, [0, 2, 1]]\n"
        "first = next(e['name'] for e in sd.engines() if e['name'] != 'cpu'"
        " and (e['type'] == 'GPU' or not any(g['type'] == 'GPU' for g in sd.engines())))\n"
        "one = sd.compute(v, t, engine=first)\n"
        "both = sd.compute(v, t, engine='opencl:all')\n"
        "cl = [e for e in sd.engines() if e['name'] != 'cpu']\n"
        "gpus = [e for e in cl if e['type'] == 'GPU']\n"
        "print(json.dumps({'engine': both.engine, 'same': bool(np.array_equal(one.raw, both.raw)"
        " and np.array_equal(one.valid_rays, both.valid_rays)),"
        " 'expected': len(gpus or cl)}))\n"
    )
    out = run_python(code, POCL_DEVICES="pthread pthread")
    assert out["expected"] >= 1
    assert out["engine"].count("opencl:") == out["expected"]
    assert out["same"]


@pytest.mark.parametrize("engine", OPENCL)
def test_reversed_faces_give_the_bits_of_the_mesh_wound_right(engine):
    # The device's tree is built from the mesh before orientation reverses faces, and its
    # records are rewritten after: the values are the cpu engine's on the clean mesh.
    vertices, triangles = load_mesh(DATA / "fandisk.obj")
    messy = triangles.copy()
    messy[::7] = messy[::7][:, [0, 2, 1]]
    clean = sd.compute(vertices, triangles, engine="cpu")
    for threads in (0, 2):  # the build beside orientation, and after it
        result = sd.compute(vertices, messy, engine=engine, threads=threads)
        assert result.flipped_faces == len(messy[::7])
        np.testing.assert_array_equal(result.raw, clean.raw)
        np.testing.assert_array_equal(result.valid_rays, clean.valid_rays)


def test_uploads_staged_through_pinned_chunks_give_the_same_bits():
    # GPUs upload (and the smoothing downloads) through two pinned chunks of 16 MiB taken in
    # turn; the hook stages every transfer on any device through 64 KiB chunks, so bunny00's
    # (3.6 MB of triangles, 3.3 MB of points) and the smoothing's cross dozens of chunk
    # boundaries, both ways; compute(smoothing='projected') uploads the cast's points' frames
    # through the side queue's chunks.
    code = (
        "import json, numpy as np, shape_diameter as sd\n"
        "from shape_diameter import _testing\n"
        "from shape_diameter.mesh_io import load_mesh\n"
        "_testing.set_overrides(opencl_staging_chunk=65536)\n"  # before the device's first use
        f"v, t = load_mesh({str(DATA / 'bunny00.off')!r})\n"
        f"engine = {OPENCL[0]!r}\n"
        "cpu = sd.compute(v, t, engine='cpu')\n"
        "cl = sd.compute(v, t, engine=engine)\n"
        "smoothed = sd.smooth(v, t, cpu.raw, 'projected', engine=engine)\n"
        "uvs = np.stack([v[:, 0] - v[:, 0].min(), v[:, 1] - v[:, 1].min()], axis=1)\n"
        "uvs = uvs / uvs.max()\n"
        "options = {'texture_size': 128}\n"
        "texture = [sd.compute(v, t, engine=e, smoothing='texture', uvs=uvs,"
        " smoothing_options=options).values for e in ('cpu', engine)]\n"
        "projected = [sd.compute(v, t, engine=e, smoothing='projected').values"
        " for e in ('cpu', engine)]\n"
        "print(json.dumps({'cast': bool(np.array_equal(cpu.raw, cl.raw)),"
        " 'texture': bool(np.array_equal(*texture)),"
        " 'projected': bool(np.array_equal(*projected)), 'smoothed': smoothed.tolist()}))\n"
    )
    out = run_python(code)
    assert out["cast"] and out["texture"]  # the texture's UVs went up the side queue's chunks
    assert out["projected"]
    vertices, triangles = load_mesh(DATA / "bunny00.off")
    raw = sd.compute(vertices, triangles, engine="cpu").raw
    direct = sd.smooth(vertices, triangles, raw, "projected", engine=OPENCL[0])
    np.testing.assert_array_equal(np.array(out["smoothed"], dtype=np.float32), direct)


@pytest.mark.parametrize("engine", ["cpu", *OPENCL])
def test_a_mesh_of_zero_area_triangles_only_casts_nothing(engine):
    # Its tree is empty (no root to read): known only once built, after the points' upload.
    V = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    F = np.array([[0, 1, 2], [3, 3, 1], [0, 0, 0]])
    with pytest.warns(RuntimeWarning, match=r"no ray of any point"):
        result = sd.compute(V, F, engine=engine)
    assert (result.raw == 0).all() and (result.valid_rays == 0).all()
    # The host's tree, or (GPUs) the device's: no tree, nothing cast.
    assert {"build", "build wait"} <= set(result.timings) or "build (device)" in result.timings


def test_stages_of_an_opencl_run_account_for_its_time():
    vertices, triangles = load_mesh(DATA / "bunny00.off")
    t = sd.compute(vertices, triangles, engine=OPENCL[0]).timings
    # 'build' overlaps 'prepare' and the upload; the others follow one another (a tree made on
    # the device, on GPUs: 'build (device)', after the upload).
    serial = sum(
        t.get(k, 0.0)
        for k in (
            "devices",
            "prepare",
            "build wait",
            "build (device)",
            "setup",
            "upload",
            "cast",
            "download",
            "fill",
            "normalize",
        )
    )
    # Not all of total: the mesh's conversion and checks come before the first stage.
    assert 0.75 * t["total"] <= serial <= t["total"] * 1.001
    if "build (device)" in t:
        assert t["build (device)"] > 0.0 and "build" not in t
    else:
        assert t["build wait"] >= 0.0 and t["build"] > 0.0


def test_progress_and_cancellation_on_opencl():
    vertices, triangles = load_mesh(DATA / "fandisk.obj")
    seen = []
    sd.compute(vertices, triangles, engine=OPENCL[0], progress=seen.append)
    assert seen[-1] == 1.0 and all(b >= a for a, b in zip(seen, seen[1:]))

    class Stop(Exception):
        pass

    def stop(fraction):
        if fraction > 0.1:
            raise Stop()

    with pytest.raises(Stop):
        sd.compute(vertices, triangles, engine=OPENCL[0], progress=stop)
    again = sd.compute(vertices, triangles, engine=OPENCL[0])  # the device still works
    assert np.isfinite(again.raw).all()


def test_auto_picks_a_gpu_or_the_cpu_engine():
    vertices, triangles = load_mesh(DATA / "cow.obj")
    result = sd.compute(vertices, triangles)
    has_gpu = any(e["type"] == "GPU" for e in sd.engines())
    assert result.engine.startswith("opencl" if has_gpu else "cpu")


def test_auto_falls_back_to_the_cpu_engine_and_says_why():
    # 'auto' picks OpenCL only for a GPU; here it is made to pick the first OpenCL device, whose
    # memory is capped below what the mesh needs, so the OpenCL run fails and the CPU runs.
    code = (
        "import json, numpy as np, shape_diameter as sd\n"
        "from shape_diameter import api\n"
        "from shape_diameter.mesh_io import load_mesh\n"
        f"v, t = load_mesh({str(DATA / 'cow.obj')!r})\n"
        "api._resolve_engine = lambda engine: 'opencl:0' if engine == 'auto' else engine\n"
        "r = sd.compute(v, t)\n"
        "cpu = sd.compute(v, t, engine='cpu')\n"
        "print(json.dumps({'engine': r.engine, 'same': bool(np.array_equal(r.raw, cpu.raw))}))\n"
    )
    out = run_python(code, SDF_OPENCL_MAX_MEMORY=1 << 16)
    assert out["engine"].startswith("cpu") and "fell back: opencl:0 failed" in out["engine"]
    assert "does not fit" in out["engine"]
    assert out["same"]


def test_a_device_lost_mid_run_is_reported_and_then_recovered_from():
    # A test override acts out a device lost at the first launch (any later one would need a
    # mesh of several launches, and a GPU casts bunny00 in one).
    code = (
        "import json, numpy as np, shape_diameter as sd\n"
        "from shape_diameter import _testing, api\n"
        "from shape_diameter.mesh_io import load_mesh\n"
        f"v, t = load_mesh({str(DATA / 'bunny00.off')!r})\n"
        "cpu = sd.compute(v, t, engine='cpu')\n"
        "with _testing.overrides(opencl_lose_device_after=0):\n"
        "    try:\n"
        "        sd.compute(v, t, engine='opencl:0')\n"
        "        error = None\n"
        "    except RuntimeError as e:\n"
        "        error = str(e)\n"
        "    api._resolve_engine = lambda engine: 'opencl:0' if engine == 'auto' else engine\n"
        "    fallback = sd.compute(v, t)\n"
        "again = sd.compute(v, t, engine='opencl:0')\n"
        "print(json.dumps({'error': error, 'fallback': fallback.engine,\n"
        "                  'fallback_same': bool(np.array_equal(fallback.raw, cpu.raw)),\n"
        "                  'again': again.engine,\n"
        "                  'again_same': bool(np.array_equal(again.raw, cpu.raw))}))\n"
    )
    out = run_python(code)
    assert "clFinish" in out["error"] and "CL_DEVICE_NOT_AVAILABLE" in out["error"]
    assert out["fallback"].startswith("cpu") and "fell back" in out["fallback"]
    assert out["fallback_same"]
    # The next run gets a fresh context and queue on the same device, and the same bits.
    assert out["again"].startswith("opencl:0") and out["again_same"]
