# SPDX-License-Identifier: GPL-3.0-or-later
"""orientation='auto': meshes wound inside out, or with some faces reversed, give the values of
the same mesh wound outward; meshes already right are left alone."""

from pathlib import Path

import numpy as np
import pytest
import shape_diameter as sd
from shape_diameter.mesh_io import load_mesh
from shapes import box, cylinder, icosphere

DATA = Path(__file__).resolve().parents[1] / "data"
RIGHT_WAY_OUT = [
    "bunny00.off",
    "armadillo.off",
    "fandisk.obj",
    "spot.obj",
    "cow.obj",
    "suzanne.obj",
    "teapot.obj",
    "ChineseDragon-10kv.off",
]


@pytest.mark.parametrize("name", RIGHT_WAY_OUT)
def test_meshes_already_outward_are_left_alone(name):
    # Including the open teapot (unwelded patches), Suzanne's doubled flap and the dragon's holes.
    vertices, triangles = load_mesh(DATA / name)
    result = sd.compute(vertices, triangles, rays=3)
    assert result.flipped_faces == 0


def test_the_inside_out_horse_is_turned_outward():
    vertices, triangles = load_mesh(DATA / "horse.ply")  # signed volume < 0 (its README)
    auto = sd.compute(vertices, triangles, rays=10)
    flipped = sd.compute(vertices, triangles, rays=10, orientation="flip")
    with pytest.warns(RuntimeWarning, match="inside out.*'as_is' trusts the winding"):
        as_is = sd.compute(vertices, triangles, rays=10, orientation="as_is")
    assert auto.flipped_faces == len(triangles)
    np.testing.assert_array_equal(auto.raw, flipped.raw)
    assert (auto.valid_rays > 0).mean() > 0.999
    # Trusting the winding, rays leave through the skin and most faces find nothing.
    assert (as_is.valid_rays == 0).mean() > 0.5


def test_scattered_reversed_faces_are_put_back():
    vertices, triangles = icosphere(1.0, 3)
    clean = sd.compute(vertices, triangles)
    rng = np.random.default_rng(4)
    reversed_ = rng.random(len(triangles)) < 0.1
    messy = triangles.copy()
    messy[reversed_] = messy[reversed_][:, [0, 2, 1]]
    before = messy.copy()
    result = sd.compute(vertices, messy)
    assert result.flipped_faces == reversed_.sum()
    np.testing.assert_array_equal(result.raw, clean.raw)
    np.testing.assert_array_equal(messy, before)  # the caller's array is untouched
    # As wound, the reversed faces (10%) keep no ray, and a warning says so.
    expected = rf"{int(reversed_.sum())} of them none: .*orientation='as_is' trusts the winding"
    with pytest.warns(RuntimeWarning, match=expected):
        as_is = sd.compute(vertices, messy, orientation="as_is")
    assert (np.abs(as_is.raw - clean.raw) > 1e-3 * clean.raw).any()


def test_reversed_faces_are_put_back_across_unwelded_seams():
    # Faces meet at positions, not only at shared vertices. A triangle soup (each
    # face on vertices of its own, as an STL or trimesh's process=False gives) and a box whose
    # sides each have their own vertices (a CAD export), some faces reversed, were left so.
    vertices, triangles = icosphere(1.0, 3)
    soup_v = vertices[triangles].reshape(-1, 3)
    soup_t = np.arange(len(soup_v)).reshape(-1, 3)
    clean = sd.compute(soup_v, soup_t)
    reversed_ = np.random.default_rng(5).random(len(soup_t)) < 0.1
    messy = soup_t.copy()
    messy[reversed_] = messy[reversed_][:, [0, 2, 1]]
    result = sd.compute(soup_v, messy)
    assert result.flipped_faces == reversed_.sum()
    np.testing.assert_array_equal(result.raw, clean.raw)
    # One side of the box, on vertices of its own, reversed: a patch of its own before.
    box_v, box_t = box(2.0, 1.0, 1.0, 4)
    corners = box_v[box_t]
    side = np.isclose(corners[:, :, 0], 1.0).all(axis=1)  # the +x side
    sides_v = np.vstack([box_v, corners[side].reshape(-1, 3)])
    sides_t = box_t.copy()
    sides_t[side] = len(box_v) + np.arange(3 * side.sum()).reshape(-1, 3)
    clean = sd.compute(sides_v, sides_t)
    messy = sides_t.copy()
    messy[side] = messy[side][:, [0, 2, 1]]
    result = sd.compute(sides_v, messy)
    assert result.flipped_faces == side.sum()
    np.testing.assert_array_equal(result.raw, clean.raw)


@pytest.mark.parametrize("points", ["faces", "vertices"])
def test_projected_smoothing_moves_points_inward_on_the_mesh_as_oriented(points):
    # compute() turns the inside-out horse outward before casting; the projected points must
    # then move along the turned mesh's inward axes too (they once took the caller's winding
    # and moved outward: values off by up to 0.04).
    vertices, triangles = load_mesh(DATA / "horse.ply")
    inside_out = sd.compute(
        vertices, triangles, rays=10, points=points, engine="cpu", smoothing="projected"
    )
    outward = sd.compute(
        vertices,
        triangles[:, [0, 2, 1]],
        rays=10,
        points=points,
        engine="cpu",
        smoothing="projected",
    )
    assert inside_out.flipped_faces == len(triangles) and outward.flipped_faces == 0
    np.testing.assert_array_equal(inside_out.raw, outward.raw)
    np.testing.assert_array_equal(inside_out.values, outward.values)
    assert not np.array_equal(outward.values, outward.raw)  # it smoothed something


@pytest.mark.parametrize("points", ["faces", "vertices"])
def test_kring_corner_weights_use_the_normals_of_the_mesh_as_oriented(points):
    # Scattered reversed faces put back by orientation: the k-ring's dihedral-angle weights
    # must see the normals as put back, not as given (a reversed neighbour looks 180 degrees
    # away: values once differed by up to 0.84 on fandisk).
    vertices, triangles = load_mesh(DATA / "fandisk.obj")
    messy = triangles.copy()
    messy[::7] = messy[::7][:, [0, 2, 1]]
    options = {"corner_angle": 30.0}
    clean = sd.compute(
        vertices,
        triangles,
        rays=10,
        points=points,
        engine="cpu",
        smoothing="kring",
        smoothing_options=options,
    )
    fixed = sd.compute(
        vertices,
        messy,
        rays=10,
        points=points,
        engine="cpu",
        smoothing="kring",
        smoothing_options=options,
    )
    assert fixed.flipped_faces == len(messy[::7])
    np.testing.assert_array_equal(fixed.raw, clean.raw)
    np.testing.assert_array_equal(fixed.values, clean.values)


def test_each_part_is_judged_on_its_own():
    small_v, small_t = icosphere(1.0, 2)
    big_v, big_t = icosphere(2.0, 2)
    vertices = np.concatenate([small_v, big_v + [10.0, 0.0, 0.0]])
    outward = np.concatenate([small_t, big_t + len(small_v)])
    inside_out = np.concatenate([small_t, big_t[:, [0, 2, 1]] + len(small_v)])
    clean = sd.compute(vertices, outward)
    result = sd.compute(vertices, inside_out)
    assert result.flipped_faces == len(big_t)
    np.testing.assert_array_equal(result.raw, clean.raw)


def test_a_hollow_spheres_inner_wall_stays_inward():
    # A shell between radii 1.5 and 2: the inner sphere, wound inward, is the cavity's wall.
    # Judged on its own it was turned outward, and the wall measured ~2.3 instead of ~0.5.
    outer_v, outer_t = icosphere(2.0, 3)
    inner_v, inner_t = icosphere(1.5, 3)
    vertices = np.concatenate([outer_v, inner_v])
    shell = np.concatenate([outer_t, inner_t[:, [0, 2, 1]] + len(outer_v)])
    result = sd.compute(vertices, shell)
    assert result.flipped_faces == 0
    as_is = sd.compute(vertices, shell, orientation="as_is")
    np.testing.assert_array_equal(result.raw, as_is.raw)
    # The wall is 0.5 thick: every face's value near it (the cone's slant rays measure a
    # little more; the ray toward the far side of the cavity is an outlier and dropped).
    assert 0.45 < np.median(result.raw) < 0.75
    # The same shell inside out as a whole is turned outward as a whole.
    turned = sd.compute(vertices, shell[:, [0, 2, 1]])
    assert turned.flipped_faces == len(shell)
    np.testing.assert_array_equal(turned.raw, as_is.raw)


def test_a_flat_open_sheet_is_not_flipped_on_rounding():
    grid = np.array([[x, y, 0.0] for y in range(4) for x in range(4)], dtype=float)
    quads = [
        (y * 4 + x, y * 4 + x + 1, y * 4 + x + 5, y * 4 + x + 4) for y in range(3) for x in range(3)
    ]
    triangles = np.array([t for a, b, c, d in quads for t in ((a, b, c), (a, c, d))])
    with pytest.warns(RuntimeWarning, match="no ray"):
        result = sd.compute(grid, triangles)
    assert result.flipped_faces == 0


def test_a_long_thin_part_inside_out_is_turned():
    # Its volume was weighed against 1e-6 x its diagonal cubed, so a cylinder
    # 2000 times longer than its radius read as flat and stayed inside out (every value 0).
    vertices, triangles = cylinder(0.005, 10.0, 32, 16)
    outward = sd.compute(vertices, triangles)
    result = sd.compute(vertices, triangles[:, [0, 2, 1]])
    assert result.flipped_faces == len(triangles)
    np.testing.assert_array_equal(result.raw, outward.raw)


def test_a_tilted_flat_sheet_is_not_flipped_on_rounding():
    # Off the axes, its float corners leave its plane by rounding: a volume of noise, either
    # sign, that the threshold must not take for a winding. The rounding grows with the
    # distance from the mesh's centre: a review's 1 x 1 sheet 1500 units from a sphere of
    # radius 1000 was turned in 25 of 80 placements.
    grid = np.array([[x, y, 0.0] for y in range(9) for x in range(9)], dtype=float) / 8 - 0.5
    quads = [
        (y * 9 + x, y * 9 + x + 1, y * 9 + x + 10, y * 9 + x + 9)
        for y in range(8)
        for x in range(8)
    ]
    sheet = np.array([t for a, b, c, d in quads for t in ((a, b, c), (a, c, d))])
    ball_v, ball_f = icosphere(1000.0, 2)
    rng = np.random.default_rng(1)
    for _ in range(12):
        turn = np.linalg.qr(rng.normal(size=(3, 3)))[0]
        v = np.vstack([ball_v, grid @ turn.T + [1500.0, 300.0, -200.0]])
        for t in (sheet, sheet[:, [0, 2, 1]]):
            with sd.collect_warnings():  # (the sheet's points find no other side)
                result = sd.compute(v, np.vstack([ball_f, t + len(ball_v)]), rays=1)
            assert result.flipped_faces == 0


def test_flip_reverses_everything_and_bad_values_are_refused():
    vertices, triangles = icosphere(1.0, 1)
    # A sphere turned inside out: every ray leaves through the skin, nothing is measured.
    with pytest.warns(RuntimeWarning, match="inside out"):
        result = sd.compute(vertices, triangles, orientation="flip")
    assert result.flipped_faces == len(triangles)
    with pytest.raises(ValueError, match="orientation must be one of"):
        sd.compute(vertices, triangles, orientation="outward")


def test_reversed_faces_let_smooth_repeat_computes_smoothing():
    """Result.reversed_faces says which faces compute() reversed: swapping two corners of those
    gives the winding it smoothed on, so smooth() on its raw values gives its values (with 10%
    of bunny's faces reversed, the caller's winding was off by up to 4x)."""
    vertices, triangles = load_mesh(DATA / "bunny00.off")
    messy = triangles.copy()
    messy[::10] = messy[::10][:, [0, 2, 1]]
    result = sd.compute(vertices, messy, rays=10, engine="cpu", smoothing="projected")
    assert result.reversed_faces is not None
    assert result.reversed_faces.sum() == result.flipped_faces > 0
    wound = messy.copy()
    wound[result.reversed_faces] = wound[result.reversed_faces][:, [0, 2, 1]]
    np.testing.assert_array_equal(
        sd.smooth(vertices, wound, result.raw, "projected", engine="cpu"), result.values
    )
    assert sd.compute(vertices, triangles, rays=10, engine="cpu").reversed_faces is None
