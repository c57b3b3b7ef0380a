# SPDX-License-Identifier: GPL-3.0-or-later
"""Checks the Blender extension's per-platform zips (scripts/build_extension.sh makes them).

Blender installs a zip only where its platform is listed, and then installs every wheel the
zip's manifest lists: a zip without its platform's wheel for one Python installs, then fails
at import in that Blender; a wheel of another platform breaks the install. So each zip must
hold, in wheels/, exactly one wheel per Python given, each built for the zip's platform, and
its manifest must list that platform alone and exactly those wheels (Blender's build writes
them into a [build.generated] table).

    python extension_zips.py DIST VERSION --platforms linux-x64 ... --pythons cp311 cp313

Exits non-zero, saying why, when a zip is missing, an extra zip of VERSION is there, or any
zip fails a check.
"""

import argparse
import os
import re
import sys
import zipfile

import tomllib

PACKAGE = "shape_diameter"
# A wheel's platform tag to Blender's platform name (as Blender's extension build maps them).
SYSTEMS = {"manylinux": "linux", "linux": "linux", "win": "windows", "macosx": "macos"}
MACHINES = {"x86_64": "x64", "amd64": "x64", "aarch64": "arm64", "arm64": "arm64"}


def blender_platform(wheel_platform):
    """manylinux_2_28_x86_64 -> linux-x64, win_arm64 -> windows-arm64, ..."""
    system = re.match(r"[a-z]+", wheel_platform).group()
    machine = next((m for m in MACHINES if wheel_platform.endswith("_" + m)), None)
    if system not in SYSTEMS or machine is None:
        return None
    return f"{SYSTEMS[system]}-{MACHINES[machine]}"


def zip_problems(path, platform, version, pythons):
    """What is wrong with one platform's zip (an empty list when nothing is)."""
    problems = []
    with zipfile.ZipFile(path) as z:
        names = z.namelist()
        wheels = sorted(n for n in names if n.startswith("wheels/"))
        by_python = {}
        for wheel in wheels:
            parts = os.path.basename(wheel)[:-4].split("-")
            if not wheel.endswith(".whl") or len(parts) != 5 or parts[:2] != [PACKAGE, version]:
                problems.append(f"{wheel}: not a {PACKAGE} {version} wheel")
                continue
            by_python.setdefault(parts[2], []).append(wheel)
            if blender_platform(parts[4]) != platform:
                problems.append(f"{wheel}: built for {parts[4]}, not {platform}")
        for py in pythons:
            found = by_python.get(py, [])
            if len(found) != 1:
                problems.append(f"{len(found)} wheels for {py} (exactly one wanted): {found}")
        for py in sorted(set(by_python) - set(pythons)):
            problems.append(f"a wheel for {py}, which is not shipped: {by_python[py]}")
        if "__init__.py" not in names:
            problems.append("no __init__.py (the add-on)")
        manifest = tomllib.loads(z.read("blender_manifest.toml").decode())
    generated = manifest.get("build", {}).get("generated", {})
    if generated.get("platforms") != [platform]:
        problems.append(f"manifest's generated platforms {generated.get('platforms')}")
    listed = sorted(os.path.normpath(w) for w in generated.get("wheels", []))
    if listed != wheels:
        problems.append(f"manifest's generated wheels {listed}, the zip holds {wheels}")
    if platform not in manifest.get("platforms", []):
        problems.append(f"manifest's platforms {manifest.get('platforms')} lack {platform}")
    return problems


def main(argv):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("dist")
    parser.add_argument("version")
    parser.add_argument("--platforms", nargs="+", required=True)
    parser.add_argument("--pythons", nargs="+", required=True)
    args = parser.parse_args(argv)
    prefix = f"{PACKAGE}-{args.version}-"
    made = {
        name[len(prefix) : -len(".zip")].replace("_", "-", 1): os.path.join(args.dist, name)
        for name in os.listdir(args.dist)
        if name.startswith(prefix) and name.endswith(".zip")
    }
    failed = False
    for platform in sorted(set(made) - set(args.platforms)):
        print(f"{made[platform]}: a zip for {platform}, which was not asked for")
        failed = True
    for platform in args.platforms:
        if platform not in made:
            print(f"{prefix}{platform.replace('-', '_')}.zip: not made")
            failed = True
            continue
        problems = zip_problems(made[platform], platform, args.version, args.pythons)
        for problem in problems:
            print(f"{made[platform]}: {problem}")
        if not problems:
            with zipfile.ZipFile(made[platform]) as z:
                wheels = [os.path.basename(n) for n in z.namelist() if n.startswith("wheels/")]
            print(f"{made[platform]}: {platform}, {', '.join(sorted(wheels))}")
        failed = failed or bool(problems)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
