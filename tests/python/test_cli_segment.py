# SPDX-License-Identifier: GPL-3.0-or-later
"""shape-diameter --segment: the labels file, the mesh coloured by segment, --json."""

import json
from pathlib import Path

import numpy as np
import pytest

trimesh = pytest.importorskip("trimesh")

import shape_diameter
from shape_diameter import cli
from shape_diameter.colormap import segment_colors
from shape_diameter.mesh_io import load_mesh

DATA = Path(__file__).resolve().parents[1] / "data"
RAYS = 12


def test_segment_writes_labels_and_colours_by_segment(tmp_path, capsys):
    source = DATA / "psb" / "241.off"
    output = tmp_path / "bird.ply"
    argv = [
        str(source),
        "-o",
        str(output),
        "--rays",
        str(RAYS),
        "--segment",
        "4",
        "--smoothness",
        "0.3",
        "--json",
        "--threads",
        "2",
    ]
    assert cli.main(argv) == 0
    report = json.loads(capsys.readouterr().out)
    labels_path = tmp_path / "bird.segments.npy"
    assert report["outputs"]["segments"] == str(labels_path)
    labels = np.load(labels_path)
    vertices, triangles = load_mesh(source)
    assert labels.dtype == np.int32 and labels.shape == (len(triangles),)
    # The same as the API on the same SDF.
    result = shape_diameter.compute(vertices, triangles, rays=RAYS, threads=2)
    expected = shape_diameter.segment(
        vertices, triangles, result.values, clusters=4, smoothness=0.3, postprocess=True
    )
    np.testing.assert_array_equal(labels, expected.labels)
    parts = report["segments"]
    assert parts["count"] == expected.segment_count == labels.max() + 1
    assert parts["clusters"] == 4 and parts["mode"] == "auto"
    assert {"graph_cut", "soft_clustering", "total"} <= set(parts["seconds"])
    mesh = trimesh.load(output, process=False)
    np.testing.assert_array_equal(mesh.visual.face_colors, segment_colors(labels))


def test_segment_without_k_takes_five_clusters_and_cgal_mode(tmp_path, capsys):
    output = tmp_path / "bearing.off"
    argv = [
        str(DATA / "psb" / "341.off"),
        "-o",
        str(output),
        "--rays",
        str(RAYS),
        "--json",
        "--segment-mode",
        "cgal",
        "--segment",
    ]
    assert cli.main(argv) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["segments"]["clusters"] <= 5 and report["segments"]["mode"] == "cgal"
    assert np.load(tmp_path / "bearing.segments.npy").max() + 1 == report["segments"]["count"]


@pytest.mark.parametrize(
    "extra, message",
    [
        (["--segment", "--points", "vertices"], "--segment needs --points faces"),
        (["--smoothness", "0.5"], "--smoothness applies to --segment"),
        (["--segment-mode", "cgal"], "--segment-mode applies to --segment"),
        (["--min-part-area", "0.01"], "--min-part-area applies to --segment"),
        (["--segment", "--min-part-area", "1"], "must be a share in [0, 1) (0.01: 1%), got 1"),
        (["--segment", "--min-part-area", "-0.1"], "must be a share in [0, 1)"),
        (["--segment", "--min-part-area", "nan"], "must be a share in [0, 1)"),
        (["--segment", "--min-part-area", "1%"], "not a number: '1%'"),
    ],
)
def test_segment_options_out_of_place_are_refused(tmp_path, capsys, extra, message):
    argv = [str(DATA / "psb" / "341.off"), "-o", str(tmp_path / "x.ply"), *extra]
    assert cli.main(argv) == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "x.ply").exists()


def test_segment_k_out_of_range_is_a_usage_error(capsys):
    assert cli.main([str(DATA / "psb" / "341.off"), "--segment", "0"]) == 2
    assert "argument --segment: must be in [1, 256], got 0" in capsys.readouterr().err


def test_min_part_area_joins_small_parts(tmp_path, capsys):
    """--min-part-area: the labels segment(min_part_area=...) gives on the same SDF, fewer
    parts than without it on an ant whose default run has parts under 3% of its area."""
    source = DATA / "psb" / "81.off"
    common = [str(source), "--rays", str(RAYS), "--json", "--threads", "2", "--segment"]
    reports = {}
    for share in ("0", "0.03"):
        out = tmp_path / share
        out.mkdir()
        argv = [*common, "-o", str(out / "ant.ply"), "--min-part-area", share]
        assert cli.main(argv) == 0
        reports[share] = json.loads(capsys.readouterr().out)["segments"]
        assert reports[share]["min_part_area"] == float(share)
    labels = np.load(tmp_path / "0.03" / "ant.segments.npy")
    vertices, triangles = load_mesh(source)
    result = shape_diameter.compute(vertices, triangles, rays=RAYS, threads=2)
    expected = shape_diameter.segment(
        vertices, triangles, result.values, postprocess=True, min_part_area=0.03
    )
    np.testing.assert_array_equal(labels, expected.labels)
    assert reports["0.03"]["count"] == expected.segment_count < reports["0"]["count"]
