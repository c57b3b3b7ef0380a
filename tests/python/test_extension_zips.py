# SPDX-License-Identifier: GPL-3.0-or-later
"""scripts/extension_zips.py, the check of the per-platform extension zips: zips laid out as
Blender's `build --split-platforms` writes them pass; a zip missing a Python's wheel (as an
empty windows-arm64 zip once was), holding another platform's wheel, or whose manifest lists
the wrong wheels fails, saying why."""

import importlib.util
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
spec = importlib.util.spec_from_file_location("extension_zips", ROOT / "scripts/extension_zips.py")
extension_zips = importlib.util.module_from_spec(spec)
spec.loader.exec_module(extension_zips)

VERSION = "0.1.0"
TAGS = {"linux-x64": "manylinux_2_28_x86_64", "windows-arm64": "win_arm64"}


def wheel(py, platform_tag):
    return f"wheels/shape_diameter-{VERSION}-{py}-{py}-{platform_tag}.whl"


def make_zip(dist, platform, wheels, listed=None):
    listed = wheels if listed is None else listed
    manifest = (
        f'id = "shape_diameter"\nversion = "{VERSION}"\nplatforms = {list(TAGS)!r}\n'
        "[build.generated]\n"
        f"platforms = [{platform!r}]\n"
        f"wheels = {['./' + w for w in listed]!r}\n"
    ).replace("'", '"')
    path = dist / f"shape_diameter-{VERSION}-{platform.replace('-', '_')}.zip"
    with zipfile.ZipFile(path, "w") as z:
        z.writestr("__init__.py", "")
        z.writestr("blender_manifest.toml", manifest)
        for w in wheels:
            z.writestr(w, b"")
    return path


def check(dist, capsys):
    args = [str(dist), VERSION, "--platforms", *TAGS, "--pythons", "cp311", "cp313"]
    status = extension_zips.main(args)
    return status, capsys.readouterr().out


def good_zips(dist):
    for platform, tag in TAGS.items():
        make_zip(dist, platform, [wheel("cp311", tag), wheel("cp313", tag)])


def test_zips_with_one_wheel_per_python_pass(tmp_path, capsys):
    good_zips(tmp_path)
    status, out = check(tmp_path, capsys)
    assert status == 0, out


def test_a_zip_without_its_wheels_fails(tmp_path, capsys):
    good_zips(tmp_path)
    make_zip(tmp_path, "windows-arm64", [])
    status, out = check(tmp_path, capsys)
    assert status == 1
    assert "0 wheels for cp311" in out and "0 wheels for cp313" in out


def test_another_platforms_wheel_fails(tmp_path, capsys):
    good_zips(tmp_path)
    make_zip(tmp_path, "windows-arm64", [wheel("cp311", "win_amd64"), wheel("cp313", "win_arm64")])
    status, out = check(tmp_path, capsys)
    assert status == 1
    assert "built for win_amd64, not windows-arm64" in out


def test_a_manifest_listing_other_wheels_fails(tmp_path, capsys):
    good_zips(tmp_path)
    both = [wheel("cp311", "win_arm64"), wheel("cp313", "win_arm64")]
    make_zip(tmp_path, "windows-arm64", both, listed=both[:1])
    status, out = check(tmp_path, capsys)
    assert status == 1
    assert "manifest's generated wheels" in out


def test_a_missing_zip_fails(tmp_path, capsys):
    good_zips(tmp_path)
    (tmp_path / f"shape_diameter-{VERSION}-linux_x64.zip").unlink()
    status, out = check(tmp_path, capsys)
    assert status == 1
    assert "linux_x64.zip: not made" in out


def test_wheel_platform_tags_map_to_blenders_names():
    expect = {
        "manylinux_2_28_x86_64": "linux-x64",
        "linux_x86_64": "linux-x64",
        "manylinux_2_28_aarch64": "linux-arm64",
        "win_amd64": "windows-x64",
        "win_arm64": "windows-arm64",
        "macosx_11_0_arm64": "macos-arm64",
        "macosx_10_15_x86_64": "macos-x64",
    }
    assert {tag: extension_zips.blender_platform(tag) for tag in expect} == expect
