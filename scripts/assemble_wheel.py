# SPDX-License-Identifier: GPL-3.0-or-later
"""Packs a cross-built module and the package's Python files into a wheel.

scripts/build_wheels.sh compiles shape_diameter._core for another platform with CMake; pip
and scikit-build-core cannot name such a wheel (they tag it for the Python that runs them), so
this writes it as the wheel format says (PEP 427, PEP 491): the package, the module, and a
.dist-info with the project's metadata (read from pyproject.toml by pyproject-metadata, the
library scikit-build-core uses, so the fields match a native build's), WHEEL with the given
tag, the console script, and RECORD with every file's hash.

    python assemble_wheel.py --module build/.../_core.cp311-win_amd64.pyd \
        --tag cp311-cp311-win_amd64 --out dist/wheels
"""

import argparse
import base64
import hashlib
import os
import sys
import zipfile

import tomllib
from pyproject_metadata import StandardMetadata

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PACKAGES = ("shape_diameter", "_shape_diameter_entry")
# A fixed time for every entry: the same inputs give the same wheel, byte for byte.
FIXED_TIME = (2020, 1, 1, 0, 0, 0)


def package_files():
    """(path in the wheel, path on disk) of the pure-Python files, sorted."""
    files = []
    for package in PACKAGES:
        top = os.path.join(ROOT, "python", package)
        for folder, dirs, names in os.walk(top):
            dirs[:] = sorted(d for d in dirs if d != "__pycache__")
            for name in sorted(names):
                if name.endswith((".pyc", ".pyo")):
                    continue
                disk = os.path.join(folder, name)
                files.append((os.path.relpath(disk, os.path.join(ROOT, "python")), disk))
    return files


def record_line(arcname, data):
    digest = base64.urlsafe_b64encode(hashlib.sha256(data).digest()).rstrip(b"=").decode()
    return f"{arcname},sha256={digest},{len(data)}"


def dist_info(metadata, tag):
    """{name: text} of the .dist-info files other than RECORD."""
    wheel = "Wheel-Version: 1.0\nGenerator: shape_diameter assemble_wheel\n"
    wheel += f"Root-Is-Purelib: false\nTag: {tag}\n"
    files = {"METADATA": str(metadata.as_rfc822()), "WHEEL": wheel}
    if metadata.scripts:
        lines = "".join(f"{k} = {v}\n" for k, v in sorted(metadata.scripts.items()))
        files["entry_points.txt"] = "[console_scripts]\n" + lines
    return files


def write_entry(archive, arcname, data):
    info = zipfile.ZipInfo(arcname, FIXED_TIME)
    info.compress_type = zipfile.ZIP_DEFLATED
    info.external_attr = 0o644 << 16
    archive.writestr(info, data)


def assemble(module, tag, out):
    with open(os.path.join(ROOT, "pyproject.toml"), "rb") as f:
        metadata = StandardMetadata.from_pyproject(tomllib.load(f), ROOT)
    name, version = metadata.canonical_name.replace("-", "_"), str(metadata.version)
    info_dir = f"{name}-{version}.dist-info"
    entries = []
    for arcname, disk in package_files():
        with open(disk, "rb") as f:
            entries.append((arcname.replace(os.sep, "/"), f.read()))
    with open(module, "rb") as f:
        entries.append((f"shape_diameter/{os.path.basename(module)}", f.read()))
    for file, text in dist_info(metadata, tag).items():
        entries.append((f"{info_dir}/{file}", text.encode()))
    record = [record_line(arcname, data) for arcname, data in entries]
    record.append(f"{info_dir}/RECORD,,")
    entries.append((f"{info_dir}/RECORD", ("\n".join(record) + "\n").encode()))

    os.makedirs(out, exist_ok=True)
    path = os.path.join(out, f"{name}-{version}-{tag}.whl")
    with zipfile.ZipFile(path + ".tmp", "w") as archive:
        for arcname, data in entries:
            write_entry(archive, arcname, data)
    os.replace(path + ".tmp", path)
    return path


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--module", required=True, help="the built _core extension module")
    parser.add_argument("--tag", required=True, help="the wheel tag, e.g. cp311-cp311-win_amd64")
    parser.add_argument("--out", required=True, help="folder for the wheel")
    args = parser.parse_args(argv)
    print(assemble(args.module, args.tag, args.out))


if __name__ == "__main__":
    sys.exit(main())
