# SPDX-License-Identifier: GPL-3.0-or-later
"""Checks a wheel's tags: WHEEL's Tag is its file name's, its module's suffix is the one that
platform's CPython imports (EXT_SUFFIX), and RECORD lists every file in it.

    python wheel_tags.py WHEEL
"""

import os
import re
import sys
import zipfile


def module_suffix(py, platform):
    if platform.startswith("win_"):
        return f".{py}-{platform}.pyd"
    if platform.startswith("macosx"):
        return f".cpython-{py[2:]}-darwin.so"
    arch = "aarch64" if platform.endswith("aarch64") else "x86_64"
    return f".cpython-{py[2:]}-{arch}-linux-gnu.so"


def main(path):
    name, version, py, abi, platform = os.path.basename(path)[:-4].split("-")
    with zipfile.ZipFile(path) as z:
        info = f"{name}-{version}.dist-info"
        tags = re.findall(r"^Tag: (.*)$", z.read(f"{info}/WHEEL").decode(), re.M)
        if tags != [f"{py}-{abi}-{platform}"]:
            sys.exit(f"{path}: WHEEL says {tags}")
        suffix = module_suffix(py, platform)
        modules = [n for n in z.namelist() if n.startswith("shape_diameter/_core")]
        if modules != [f"shape_diameter/_core{suffix}"]:
            sys.exit(f"{path}: modules {modules}, expected _core{suffix}")
        record = z.read(f"{info}/RECORD").decode().splitlines()
        if {line.split(",")[0] for line in record} != set(z.namelist()):
            sys.exit(f"{path}: RECORD does not list the wheel's files")
    print(f"{os.path.basename(path)}: Tag {tags[0]}, module _core{suffix}")


if __name__ == "__main__":
    main(sys.argv[1])
