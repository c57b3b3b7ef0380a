# SPDX-License-Identifier: GPL-3.0-or-later
"""The UV layout (tiles, overlapping shells) found before texture smoothing's work and said
then, and found once: shape_diameter.uv_layout(), and compute() and smooth() that find it
first or take it."""

import numpy as np
import pytest
import shape_diameter
from shape_diameter import collect_warnings, smooth, uv_layout
from test_smoothing import DATA, _read_obj

OVERLAP = "faces have UVs overlapping another UV island's"


@pytest.fixture(scope="module")
def stacked():
    """spot.obj and a copy beside it with the same UVs: two shells, every face overlapping
    one of the other's."""
    v, t, uvs, _ = _read_obj(DATA / "spot.obj")
    both_v = np.vstack([v, v + [3.0, 0.0, 0.0]])
    both_t = np.vstack([t, t + len(v)])
    return both_v, both_t, np.concatenate([uvs, uvs]).astype(np.float32)


def test_the_layout_of_stacked_shells(stacked):
    v, t, uvs = stacked
    layout = uv_layout(v, t, uvs)
    assert layout.face_count == len(t) and layout.tiles == (1001,)
    assert layout.pages == 2 and not layout.overlaps_unparted
    # Each of the copies' faces lies on its twin (a few slivers may overlap too little).
    assert 0.95 * len(t) <= layout.faces_overlapping <= len(t)
    assert layout.faces_outside == 0 and layout.seconds > 0
    assert len(layout.warnings) == 1 and OVERLAP in layout.warnings[0]
    assert f"({layout.pages} images in all)" in layout.warnings[0]


def test_a_layout_on_tiles_with_faces_outside():
    v, t, uvs, _ = _read_obj(DATA / "spot.obj")
    moved = uvs.copy()
    moved[: len(t) // 2] += np.float32(1.0)  # half the faces one tile up and right: 1012
    moved[len(t) // 2 :: 2] -= np.float32(5.0)  # a quarter at negative UVs: in no tile
    layout = uv_layout(v, t, moved)
    assert 1012 in layout.tiles
    assert layout.faces_outside >= len(t) // 4 - 1
    assert any("outside every UDIM tile" in w for w in layout.warnings)


def _said_before_the_work(call):
    """Runs call(progress) collecting the package's warnings; returns (warnings, how many
    had been said when the work first reported progress)."""
    at_first = []
    with collect_warnings() as caught:

        def progress(fraction):
            if not at_first:
                at_first.append(len(caught))

        call(progress)
    return caught, at_first[0]


def test_smooth_says_the_overlaps_before_its_work(stacked):
    v, t, uvs = stacked
    values = np.linspace(0.1, 1.0, len(t), dtype=np.float32)
    caught, said = _said_before_the_work(
        lambda progress: smooth(
            v, t, values, "texture", uvs=uvs, texture_size=64, progress=progress
        )  # fmt: skip
    )
    assert [OVERLAP in w for w in caught] == [True] and said == 1


def test_compute_says_the_overlaps_before_the_cast(stacked):
    v, t, uvs = stacked
    caught, said = _said_before_the_work(
        lambda progress: shape_diameter.compute(
            v,
            t,
            rays=8,
            smoothing="texture",
            uvs=uvs,
            smoothing_options={"texture_size": 64},
            progress=progress,
        )  # fmt: skip
    )
    assert sum(OVERLAP in w for w in caught) == 1 and said >= 1


def test_a_layout_found_first_is_not_found_again(stacked, monkeypatch):
    # Given back, the layout is used as it is: the same values as finding it in the call, no
    # search in the call, and no second warning (its finder said it).
    from shape_diameter import uv_plan

    v, t, uvs = stacked
    values = np.linspace(0.1, 1.0, len(t), dtype=np.float32)
    with collect_warnings():
        expected = smooth(v, t, values, "texture", uvs=uvs, texture_size=64)
    layout = uv_layout(v, t, uvs)
    calls = []
    search = uv_plan._core.uv_layout
    monkeypatch.setattr(uv_plan._core, "uv_layout", lambda *a: calls.append(a) or search(*a))
    with collect_warnings() as caught:
        out = smooth(v, t, values, "texture", uvs=uvs, texture_size=64, uv_layout=layout)
        computed = shape_diameter.compute(
            v, t, rays=8, smoothing="texture", uvs=uvs,
            smoothing_options={"texture_size": 64, "uv_layout": layout},
        )  # fmt: skip
    np.testing.assert_array_equal(out, expected)
    assert calls == [] and not [w for w in caught if OVERLAP in w]
    with collect_warnings():
        found = shape_diameter.compute(v, t, rays=8, smoothing="texture", uvs=uvs,
                                       smoothing_options={"texture_size": 64})  # fmt: skip
    np.testing.assert_array_equal(computed.values, found.values)


def test_a_layout_of_other_faces_or_points_is_refused(stacked):
    v, t, uvs = stacked
    layout = uv_layout(v, t, uvs)
    values = np.ones(len(v), dtype=np.float32)
    with pytest.raises(ValueError, match="points='vertices'"):
        smooth(v, t, values, "texture", uvs=uvs, points="vertices", uv_layout=layout)
    half = len(t) // 2
    with pytest.raises(ValueError, match="another mesh"):
        smooth(v, t[:half], np.ones(half, np.float32), "texture", uvs=uvs[:half],
               uv_layout=layout)  # fmt: skip
    with pytest.raises(ValueError, match="another weld_tolerance"):
        smooth(v, t, np.ones(len(t), np.float32), "texture", uvs=uvs, uv_layout=layout,
               weld_tolerance=1e-4)  # fmt: skip
    # The same face count on a mesh of more vertices (its islands would index past the end of
    # the layout's vertices), and other UVs on the same mesh: refused, not used.
    more = np.concatenate([v, v + 10.0])
    with pytest.raises(ValueError, match="another mesh or other UVs"):
        smooth(more, t + len(v), np.ones(len(more), np.float32), "texture", uvs=uvs,
               points="vertices", uv_layout=uv_layout(v, t, uvs, points="vertices"))  # fmt: skip
    moved = np.array(uvs, dtype=np.float32)
    moved[..., 0] = 0.5 * moved[..., 0]
    with pytest.raises(ValueError, match="another mesh or other UVs"):
        smooth(v, t, np.ones(len(t), np.float32), "texture", uvs=moved, uv_layout=layout)
    with pytest.raises(ValueError, match="uv_layout must be"):
        smooth(v, t, np.ones(len(t), np.float32), "texture", uvs=uvs, uv_layout="yes")


def test_vertex_values_with_a_layout_for_vertices(stacked):
    v, t, uvs = stacked
    values = np.linspace(0.1, 1.0, len(v), dtype=np.float32)
    with collect_warnings():
        expected = smooth(v, t, values, "texture", uvs=uvs, texture_size=64)
    layout = uv_layout(v, t, uvs, points="vertices")
    assert layout.for_vertices
    out = smooth(v, t, values, "texture", uvs=uvs, texture_size=64, uv_layout=layout)
    np.testing.assert_array_equal(out, expected)


def test_the_command_line_says_the_overlaps_before_computing(tmp_path, capsys, monkeypatch):
    # spot.obj with every face twice (a second shell on the same UVs): the warning is printed
    # once, before compute() starts, and compute() gets the layout found.
    from shape_diameter import batch_job, cli

    lines = (DATA / "spot.obj").read_text().splitlines()
    faces = [line for line in lines if line.startswith("f ")]
    vertex_count = sum(line.startswith("v ") for line in lines)
    moved = [line for line in lines if line.startswith(("v ", "vt "))]
    moved += [f"v {float(p[1]) + 3.0!r} {p[2]} {p[3]}"
              for p in (line.split() for line in lines if line.startswith("v "))]  # fmt: skip
    again = []
    for face in faces:
        corners = [c.split("/") for c in face.split()[1:]]
        again.append("f " + " ".join(f"{int(c[0]) + vertex_count}/{c[1]}" for c in corners))
    obj = tmp_path / "spot_twice.obj"
    obj.write_text("\n".join(moved + faces + again) + "\n")
    seen = []
    compute = batch_job.compute

    def recording(*args, **kwargs):
        seen.append((capsys.readouterr().err, kwargs["smoothing_options"]["uv_layout"]))
        return compute(*args, **kwargs)

    monkeypatch.setattr(batch_job, "compute", recording)
    argv = [str(obj), "--rays", "8", "--engine", "cpu", "--smooth", "texture",
            "--texture-size", "64", "--values", str(tmp_path / "values.npy")]  # fmt: skip
    assert cli.main(argv) == 0
    (before, layout), after = seen[0], capsys.readouterr().err
    assert before.count(OVERLAP) == 1 and OVERLAP not in after
    assert layout.faces_overlapping > 0.9 * layout.face_count
