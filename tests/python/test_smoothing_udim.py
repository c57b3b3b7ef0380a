# SPDX-License-Identifier: GPL-3.0-or-later
"""Texture smoothing of UDIM layouts (UVs on tiles 1001+) and of overlapping UV islands: each
tile, and each overlapping island, is smoothed as an image of its own."""

import warnings

import numpy as np
import pytest
import shape_diameter
from shape_diameter import _testing, smooth
from test_smoothing import DATA, _read_obj

# Tiles as (column, row) offsets: 1001, 1002, 1013, 1021.
TILES = {1001: (0, 0), 1002: (1, 0), 1013: (2, 1), 1021: (0, 2)}


@pytest.fixture(scope="module")
def spot_tiles():
    """spot.obj's UV islands spread over four tiles. Its layout is first scaled into
    [0.01, 0.99] (a few faces reach just over the square's edge, and would belong to the
    neighbouring tile once moved). The tiled UVs are float32 (adding whole numbers rounds
    them); `square` is each tile's islands moved back into the square by subtracting them,
    which is exact in floats (Sterbenz: u - k for u in [k, k + 1], k >= 1)."""
    v, t, uvs, _ = _read_obj(DATA / "spot.obj")
    lo, hi = uvs.min(axis=(0, 1)), uvs.max(axis=(0, 1))
    scaled = (np.float32(0.01) + np.float32(0.98) * (uvs - lo) / (hi - lo)).astype(np.float32)
    islands = _testing.uv_islands(v, t, scaled, 1e-6)
    numbers = np.array(list(TILES))
    face_tile = numbers[islands % len(numbers)]
    offset = np.array([TILES[n] for n in face_tile], dtype=np.float32)
    tiled = (scaled + offset[:, None, :]).astype(np.float32)
    square = (tiled - offset[:, None, :]).astype(np.float32)
    np.testing.assert_allclose(square, scaled, atol=1e-6)
    faces = shape_diameter.compute(v, t, rays=16).raw
    vertices = shape_diameter.compute(v, t, rays=16, points="vertices").raw
    return v, t, square, tiled, offset, face_tile, faces, vertices


def _alone(v, t, values, uvs, points, **options):
    """Smoothing of faces t alone (every vertex kept), without a warning."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return smooth(v, t, values, "texture", uvs=uvs, points=points, **options)


@pytest.mark.parametrize("engine", ["cpu", "auto"])
def test_udim_tiles_give_each_tile_the_values_of_its_islands_in_one_square(spot_tiles, engine):
    v, t, square, tiled, offset, face_tile, faces, _ = spot_tiles
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a UDIM layout is not outside anything
        out = smooth(v, t, faces, "texture", uvs=tiled, texture_size=256, engine=engine,
                     return_image=True)  # fmt: skip
    assert sorted(out.tiles) == sorted(TILES)
    for number in TILES:
        mine = face_tile == number
        assert mine.sum() > 100
        back = square[mine]
        # The values of a face depend only on the faces of its tile: bit for bit.
        alone = _alone(v, t[mine], faces[mine], back, "faces", texture_size=256, engine=engine,
                       return_image=True)  # fmt: skip
        np.testing.assert_array_equal(out.values[mine], alone.values)
        image, mask = out.tiles[number]
        assert image.shape == (256, 256)
        np.testing.assert_array_equal(image, alone.image)
        np.testing.assert_array_equal(mask, alone.mask)
    np.testing.assert_array_equal(out.image, out.tiles[1001][0])
    # Smoothing did something: the tiled result is not the input.
    assert np.abs(out.values - faces).max() > 0.01 * faces.max()


def test_udim_tiles_on_vertex_values(spot_tiles):
    # A vertex whose corners all lie in one tile takes that tile's value; one on a seam between
    # islands of two tiles takes the mean over its corners of each tile's value there.
    v, t, square, tiled, offset, face_tile, _, vertices = spot_tiles
    out = _alone(v, t, vertices, tiled, "vertices", texture_size=256)
    expected_sum = np.zeros(len(v))
    corners = np.zeros(len(v))
    for number in TILES:
        mine = face_tile == number
        alone = _alone(v, t[mine], vertices, square[mine], "vertices", texture_size=256)
        used = t[mine].ravel()
        np.add.at(expected_sum, used, alone[used].astype(np.float64))
        np.add.at(corners, used, 1.0)
    expected = (expected_sum / corners).astype(np.float32)
    tiles_per_vertex = np.zeros(len(v), dtype=int)
    for number in TILES:
        touched = np.zeros(len(v), dtype=bool)
        touched[t[face_tile == number].ravel()] = True
        tiles_per_vertex += touched
    one = tiles_per_vertex == 1
    assert one.sum() > 0.8 * len(v) and (~one).sum() > 10  # seams between tiles exist
    np.testing.assert_array_equal(out[one], expected[one])
    np.testing.assert_allclose(out[~one], expected[~one], rtol=1e-6)


def test_udim_matches_the_one_square_layout_away_from_island_borders(spot_tiles):
    # The same islands all in one square differ only where another island's margin or blur
    # reach came near (islands of other tiles are no longer there): most faces are equal.
    v, t, square, tiled, _, _, faces, _ = spot_tiles
    one = _alone(v, t, faces, square, "faces", texture_size=256)
    tiles = _alone(v, t, faces, tiled, "faces", texture_size=256)
    equal = np.isclose(one, tiles, rtol=1e-6, atol=0.0)
    assert equal.mean() > 0.9
    assert np.median(np.abs(one - tiles) / one) < 1e-6


def test_only_uvs_outside_every_tile_are_left_out(spot_tiles):
    v, t, square, _, _, _, faces, _ = spot_tiles
    far = square.copy()
    far[: len(t) // 2] += np.float32(-2.0)  # u and v < 0: no tile
    with pytest.warns(RuntimeWarning, match=rf"^{len(t) // 2} of {len(t)} faces have UVs "
                                            r"outside every UDIM tile"):  # fmt: skip
        out = smooth(v, t, faces, "texture", uvs=far, texture_size=128)
    np.testing.assert_array_equal(out[: len(t) // 2], faces[: len(t) // 2])
    assert not np.array_equal(out[len(t) // 2 :], faces[len(t) // 2 :])
    with pytest.warns(RuntimeWarning, match=r"outside every UDIM tile .*the images leave them"):
        result = smooth(v, t, faces, "texture", uvs=far, texture_size=128, return_image=True)
    assert list(result.tiles) == [1001]


@pytest.mark.parametrize("points", ["faces", "vertices"])
def test_stacked_copies_of_a_shell_do_not_mix(points):
    # Two copies of spot on the same UVs (a stacked shell), with different values: each copy's
    # smoothed values are those of smoothing it alone.
    v, t, uvs, _ = _read_obj(DATA / "spot.obj")
    both_v = np.vstack([v, v + [3.0, 0.0, 0.0]])
    both_t = np.vstack([t, t + len(v)])
    both_uvs = np.concatenate([uvs, uvs])
    n = len(t) if points == "faces" else len(v)
    rng = np.random.default_rng(5)
    first = rng.uniform(1.0, 2.0, n).astype(np.float32)
    second = rng.uniform(5.0, 9.0, n).astype(np.float32)
    drawn = 2 * int((~((uvs[..., 0] < 0) | (uvs[..., 1] < 0)).all(axis=1)).sum())  # in a tile
    with pytest.warns(RuntimeWarning, match=rf"^{drawn} of {2 * len(t)} faces have UVs "
                                            r"overlapping another UV island's .*\(2 images in "
                                            r"all\)"):  # fmt: skip
        out = smooth(both_v, both_t, np.concatenate([first, second]), "texture", uvs=both_uvs,
                     points=points, texture_size=128)  # fmt: skip
    alone_first = _alone(v, t, first, uvs, points, texture_size=128)
    alone_second = _alone(v, t, second, uvs, points, texture_size=128)
    np.testing.assert_array_equal(out[:n], alone_first)
    np.testing.assert_array_equal(out[n:], alone_second)


def test_mirrored_half_overlapping_is_reported_and_kept_apart():
    # A mirrored layout: the right half's UVs mirror the left half's onto the same area. Only
    # the overlapping faces are counted; smoothing keeps each half to itself.
    v, t, uvs, _ = _read_obj(DATA / "spot.obj")
    islands = _testing.uv_islands(v, t, uvs, 1e-6)
    big = np.argmax(np.bincount(islands))
    mine = islands == big
    mirrored = uvs[mine].copy()
    mirrored[..., 0] = 1.0 - mirrored[..., 0]  # the island mirrored in u
    lo = mirrored.min(axis=(0, 1))
    target = uvs[mine].min(axis=(0, 1))
    mirrored += (target - lo).astype(np.float32)  # over the original island
    both_t = np.vstack([t[mine], t[mine] + len(v)])
    both_v = np.vstack([v, v + [3.0, 0.0, 0.0]])
    both_uvs = np.concatenate([uvs[mine], mirrored]).astype(np.float32)
    values = np.concatenate(
        [np.full(mine.sum(), 1.0, np.float32), np.full(mine.sum(), 4.0, np.float32)]
    )
    with pytest.warns(RuntimeWarning, match=r"faces have UVs overlapping another UV island's"):
        out = smooth(both_v, both_t, values, "texture", uvs=both_uvs, texture_size=128)
    np.testing.assert_array_equal(out, values)  # constant per shell: no mixing at all


def test_command_line_smooths_a_udim_obj_per_tile(tmp_path, capsys):
    # spot.obj with its texture coordinates moved to tile 1002: smoothed there, with no word
    # about UVs outside anything (they were all left out, with a warning).
    from shape_diameter import cli

    text = (DATA / "spot.obj").read_text().splitlines()
    moved = []
    for line in text:
        p = line.split()
        if p and p[0] == "vt":
            line = f"vt {float(p[1]) + 1.0!r} {p[2]}"
        moved.append(line)
    obj = tmp_path / "spot_udim.obj"
    obj.write_text("\n".join(moved) + "\n")
    values = tmp_path / "values.npy"
    argv = [str(obj), "--rays", "12", "--engine", "cpu", "--smooth", "texture",
            "--texture-size", "64", "--values", str(values)]  # fmt: skip
    assert cli.main(argv) == 0
    assert "outside" not in capsys.readouterr().err
    v, t, uvs = shape_diameter.load_mesh(obj, uvs=True)
    assert uvs[..., 0].min() > 0.9  # on tile 1002 (and a few faces' corners on 1001)
    expected = shape_diameter.compute(
        v, t, rays=12, engine="cpu", smoothing="texture", uvs=uvs,
        smoothing_options={"texture_size": 64},
    )  # fmt: skip
    np.testing.assert_array_equal(np.load(values), expected.values)
    assert not np.array_equal(expected.values, expected.raw)


@pytest.mark.parametrize("engine", ["cpu", "auto"])
def test_compute_smooths_a_udim_layout_as_smooth_does(spot_tiles, engine):
    # compute() prepares the texture beside the cast (on a device, uploaded): a layout of
    # several pages runs page by page all the same.
    v, t, _, tiled, _, _, _, _ = spot_tiles
    options = {"texture_size": 128}
    result = shape_diameter.compute(v, t, rays=16, engine=engine, smoothing="texture", uvs=tiled,
                                    smoothing_options=options)  # fmt: skip
    alone = smooth(v, t, result.raw, "texture", uvs=tiled, engine=engine, **options)
    np.testing.assert_array_equal(result.values, alone)
    assert not np.array_equal(result.values, result.raw)
