# SPDX-License-Identifier: GPL-3.0-or-later
# Sourced by scripts/check_wheels.sh (after downloads.sh): a Debian 11 (bullseye, glibc 2.31)
# root to run the linux-x64 wheels on an older glibc than this machine's. Debian 11 ships
# Python 3.9 only, and Debian 12's python3.11 needs glibc 2.34: CPython 3.11 and 3.13 are
# compiled inside that root, by its own gcc against its own glibc, from Debian's source
# tarballs (scripts/downloads.sh), so they need no newer glibc than the root has. Made once
# into build/bullseye (debootstrap from Debian's mirror, as root; then kept).
BULLSEYE=build/bullseye
BULLSEYE_PACKAGES=gcc,make,libc6-dev,zlib1g-dev,libffi-dev

bullseye_root() {
  if [ ! -f "$BULLSEYE/.complete" ]; then
    command -v debootstrap >/dev/null ||
      DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends debootstrap >/dev/null
    rm -rf "$BULLSEYE"
    debootstrap --variant=minbase --include="$BULLSEYE_PACKAGES" bullseye "$BULLSEYE" \
      http://deb.debian.org/debian >&2
    touch "$BULLSEYE/.complete"
  fi
  echo "$ROOT/$BULLSEYE"
}

# bullseye_python TAG: the path, inside the root, of that CPython (compiled on first use:
# minutes, with plain ./configure: the run needs a working interpreter, not a fast one).
bullseye_python() {
  local root ver=${1#cp} source dir
  root=$(bullseye_root)
  ver=${ver:0:1}.${ver:1}
  if [ ! -x "$root/opt/python$ver/bin/python$ver" ]; then
    source=$(cpython_source "$1")
    dir=$root/src/python$ver
    rm -rf "$dir" && mkdir -p "$dir"
    tar -xf "$source" -C "$dir" --strip-components=1
    chroot "$root" /bin/sh -c "cd /src/python$ver && ./configure -q --prefix=/opt/python$ver \
      --without-ensurepip && make -s -j2 && make -s install" >&2
    rm -rf "$dir"
  fi
  echo "/opt/python$ver/bin/python$ver"
}
