#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Builds the Blender extension, one zip per Blender platform:
#
#   scripts/build_extension.sh                  dist/shape_diameter-<version>-linux_x64.zip from
#                                               wheels built by this machine's compiler (what
#                                               scripts/test_blender.sh and the demo install)
#   scripts/build_extension.sh all | TARGET...  the zips of those platforms (linux-x64
#                                               linux-arm64 windows-x64 windows-arm64 macos-arm64
#                                               macos-x64) from the wheels scripts/build_wheels.sh
#                                               cross-builds for them (manylinux_2_28 on Linux)
#
#  1. one wheel of the package per CPython that Blender ships: cp311 (Blender 4.2 LTS to 5.0)
#     and cp313 (Blender 5.1 and later). Without targets: built by those Pythons
#     (scripts/pythons.sh finds them) in build venvs (build/ext-venv-cpXY) without build
#     isolation, into cached CMake build directories (build/ext-<wheel tag>), so a second run
#     recompiles only what changed. With targets: scripts/build_wheels.sh TARGET... (zig's
#     clang, incremental too) into dist/wheels;
#  2. the extension tree in build/extension: addon/*, blender_manifest.toml, wheels/; the
#     staged manifest's `platforms` and `wheels` say exactly what was built;
#  3. the zips, built and validated by Blender's own extension logic (blender_ext.py, the code
#     behind `blender --command extension build --split-platforms` and `... validate`), run by
#     a plain Python from the bpy package in .venv-bpy45 (made here when missing);
#  4. each zip's content (scripts/extension_zips.py): exactly one wheel per Python, built for
#     its platform, and its manifest listing that platform and those wheels alone.
#
# Environment: PY311, PY313 (interpreters), BPY45_VENV (default .venv-bpy45), SDF_REUSE_WHEELS,
# SDF_WHEELS (default "cp311 cp313"; the demo, which renders with Blender 4.5, builds only
# cp311, so it needs no Python 3.13: the zip then lists only that wheel).
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD

source scripts/pythons.sh
SDF_WHEELS=${SDF_WHEELS:-cp311 cp313}
need_python PY311 3.11 "the extension's wheel for Blender 4.2 to 5.0"
case " $SDF_WHEELS " in *" cp313 "*) need_python PY313 3.13 "the extension's wheel for Blender 5.1 and later" ;; esac
BPY45_VENV=${BPY45_VENV:-.venv-bpy45}
log() { echo "build_extension: $*"; }
source scripts/wheel_files.sh
TARGETS=("$@")
[ "${TARGETS[*]}" != all ] || TARGETS=("${ALL_TARGETS[@]}")
for t in "${TARGETS[@]}"; do
  case " ${ALL_TARGETS[*]} " in *" $t "*) ;; *) log "unknown target $t (all, ${ALL_TARGETS[*]})" >&2; exit 2 ;; esac
done

# Debian packages the C++ core needs (the same ones scripts/setup.sh installs), plus the X11
# client libraries that bpy links (used by test_blender.sh; bpy is installed here for the build
# logic, and importing bpy is how its version is read).
APT_PACKAGES=(build-essential cmake ninja-build libglm-dev
              libsm6 libxrender1 libxi6 libxkbcommon0 libgl1 libegl1 libxxf86vm1 libxfixes3)
missing=()
for p in "${APT_PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  log "installing Debian packages: ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

VERSION=$("$PY311" -c 'import tomllib; print(tomllib.load(open("pyproject.toml", "rb"))["project"]["version"])')
MANIFEST_VERSION=$("$PY311" -c 'import tomllib; print(tomllib.load(open("blender_manifest.toml", "rb"))["version"])')
if [ "$VERSION" != "$MANIFEST_VERSION" ]; then
  log "error: pyproject.toml says version $VERSION, blender_manifest.toml says $MANIFEST_VERSION" >&2
  exit 1
fi

# build_native_wheels: the package's wheels for this machine, one per Python in SDF_WHEELS,
# into $WHEEL_DIR, built by each Python from the source tree with this machine's compiler.
build_native_wheels() {
  local pythons=() tag py venv
  for tag in $SDF_WHEELS; do
    case $tag in cp311) pythons+=("$PY311") ;; cp313) pythons+=("$PY313") ;; esac
  done
  if [ "${SDF_REUSE_WHEELS:-0}" = 1 ] &&
     [ "$(ls "$WHEEL_DIR"/*.whl 2>/dev/null | wc -l)" = "${#pythons[@]}" ]; then
    log "reusing the wheels in $WHEEL_DIR"
    return
  fi
  rm -rf "$WHEEL_DIR" && mkdir -p "$WHEEL_DIR"
  for py in "${pythons[@]}"; do
    tag=$("$py" -c 'import sys; print(f"cp{sys.version_info[0]}{sys.version_info[1]}")')
    venv=build/ext-venv-$tag
    if [ ! -x "$venv/bin/python" ]; then
      log "creating build venv $venv ($("$py" --version))"
      "$py" -m venv "$venv"
      "$venv/bin/python" -m pip install -q --upgrade pip
    fi
    "$venv/bin/python" -m pip install -q "scikit-build-core>=0.10" "pybind11>=2.12"
    log "building the $tag wheel"
    # Without the test-only module shape_diameter._testing: nothing in Blender uses it.
    "$venv/bin/python" -m pip wheel . --no-deps --no-build-isolation -q -w "$WHEEL_DIR" \
      -C build-dir="build/ext-{wheel_tag}" -C cmake.define.SDF_BUILD_TESTING_MODULE=OFF
  done
}

# 1. Wheels, into $WHEEL_DIR. SDF_REUSE_WHEELS=1 keeps the last ones (to iterate on addon/).
for tag in $SDF_WHEELS; do
  case $tag in cp311 | cp313) ;; *) log "error: SDF_WHEELS names $tag (cp311 or cp313)" >&2; exit 2 ;; esac
done
if [ ${#TARGETS[@]} -gt 0 ]; then
  PLATFORMS=("${TARGETS[@]}")
  WHEEL_DIR=build/ext-cross-wheels
  [ "${SDF_REUSE_WHEELS:-0}" = 1 ] || SDF_WHEEL_PYTHONS=$SDF_WHEELS bash scripts/build_wheels.sh "${TARGETS[@]}"
  rm -rf "$WHEEL_DIR" && mkdir -p "$WHEEL_DIR"
  for target in "${TARGETS[@]}"; do
    for tag in $SDF_WHEELS; do
      wheel=$(wheel_for "$target" "$tag")
      [ -n "$wheel" ] || { log "error: no $target $tag wheel in $WHEELS" >&2; exit 1; }
      cp "$wheel" "$WHEEL_DIR/"
    done
  done
else
  PLATFORMS=(linux-x64)
  WHEEL_DIR=build/ext-wheels
  build_native_wheels
fi
ls "$WHEEL_DIR"

# 2. The extension tree. The staged manifest's platforms and wheels are those just built: each
# platform must be one the repository's manifest lists, and so must each cross-built wheel
# (the release's; this machine's own linux_x86_64 wheels stand in for the manylinux ones).
STAGE=build/extension
rm -rf "$STAGE"
mkdir -p "$STAGE/wheels"
cp -r addon/. "$STAGE/"
find "$STAGE" -name __pycache__ -type d -prune -exec rm -rf {} +
cp blender_manifest.toml "$STAGE/"
cp "$WHEEL_DIR"/*.whl "$STAGE/wheels/"
"$PY311" - "$STAGE" "${#TARGETS[@]}" "${PLATFORMS[@]}" <<'PYEOF'
import os, re, sys, tomllib
stage, cross, platforms = sys.argv[1], sys.argv[2] != "0", sys.argv[3:]
path = os.path.join(stage, "blender_manifest.toml")
manifest = tomllib.load(open(path, "rb"))
wheels = sorted(f"./wheels/{f}" for f in os.listdir(os.path.join(stage, "wheels")))
unknown = [p for p in platforms if p not in manifest["platforms"]]
unknown += [w for w in wheels if cross and w not in manifest["wheels"]]
if unknown:
    sys.exit(f"build_extension: blender_manifest.toml does not list {unknown}")
def toml_list(items):
    return "[\n" + "".join(f'  "{i}",\n' for i in items) + "]"
text = open(path).read()
for key, items in (("platforms", platforms), ("wheels", wheels)):
    text, n = re.subn(rf"^{key} = \[[^\]]*\]", f"{key} = {toml_list(items)}", text, count=1,
                      flags=re.M)
    if n != 1:
        sys.exit(f"build_extension: no `{key} = [...]` in blender_manifest.toml")
open(path, "w").write(text)
PYEOF

# 3. Blender's build and validate logic, from the bpy package.
# The same requirements (and marker file) as scripts/test_blender.sh, which tests in this venv.
BPY45_REQUIREMENTS=("bpy>=4.5,<4.6" "numpy<2" "pytest>=7")
if [ ! -x "$BPY45_VENV/bin/python" ] ||
   [ "$(cat "$BPY45_VENV/.requirements" 2>/dev/null)" != "${BPY45_REQUIREMENTS[*]}" ]; then
  log "creating $BPY45_VENV (bpy 4.5 LTS, Python 3.11, numpy < 2)"
  rm -rf "$BPY45_VENV"
  "$PY311" -m venv "$BPY45_VENV"
  "$BPY45_VENV/bin/python" -m pip install -q --upgrade pip
  "$BPY45_VENV/bin/python" -m pip install -q "${BPY45_REQUIREMENTS[@]}"
  echo "${BPY45_REQUIREMENTS[*]}" > "$BPY45_VENV/.requirements"
fi
BPY_SCRIPTS=$("$BPY45_VENV/bin/python" - <<'EOF'
import glob, os, importlib.util
root = os.path.dirname(importlib.util.find_spec("bpy").origin)
# bpy/<major.minor>/scripts, found without importing bpy (which starts Blender).
print(sorted(glob.glob(os.path.join(root, "[0-9]*.[0-9]*", "scripts")))[-1])
EOF
)
BLENDER_EXT=$BPY_SCRIPTS/addons_core/bl_pkg/cli/blender_ext.py
VALID_TAGS=$BPY_SCRIPTS/modules/_bpy_internal/extensions/tags.py
mkdir -p dist
rm -f dist/shape_diameter-"$VERSION"-*.zip
log "building the extension with $BLENDER_EXT"
"$BPY45_VENV/bin/python" "$BLENDER_EXT" build --source-dir "$STAGE" --output-dir dist \
  --split-platforms --valid-tags "$VALID_TAGS"
for platform in "${PLATFORMS[@]}"; do
  ZIP=dist/shape_diameter-$VERSION-${platform/-/_}.zip
  [ -f "$ZIP" ] || { log "error: $ZIP was not made" >&2; ls dist >&2; exit 1; }
  log "validating $ZIP"
  "$BPY45_VENV/bin/python" "$BLENDER_EXT" validate "$ZIP" --valid-tags "$VALID_TAGS"
done

# 4. What each zip holds.
"$PY311" scripts/extension_zips.py dist "$VERSION" --platforms "${PLATFORMS[@]}" --pythons $SDF_WHEELS
ls -l dist/shape_diameter-"$VERSION"-*.zip
