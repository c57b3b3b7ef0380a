# SPDX-License-Identifier: GPL-3.0-or-later
"""Static checks of a macOS extension module (Mach-O), for builds that cannot run here.

    python macho_check.py MODULE.so --min-os 11.0 [--signed]

Checks, from the file's load commands: the minimum macOS it asks for (LC_BUILD_VERSION or
LC_VERSION_MIN_MACOSX) is the one given; the only library it links is libSystem (no
libpython: the interpreter's symbols are looked up when it loads the module, as
`-undefined dynamic_lookup` asks); with --signed, that an ad-hoc code signature is there and
its page hashes match the file (arm64 macOS refuses to load code whose signature does not
match, e.g. after a strip or an edit once linked). Exits non-zero with the reason otherwise.
"""

import argparse
import hashlib
import struct
import sys

MH_MAGIC_64 = 0xFEEDFACF
LC_LOAD_DYLIB, LC_LOAD_WEAK_DYLIB, LC_REEXPORT_DYLIB = 0xC, 0x80000018, 0x8000001F
LC_VERSION_MIN_MACOSX, LC_BUILD_VERSION, LC_CODE_SIGNATURE = 0x24, 0x32, 0x1D
CSMAGIC_EMBEDDED_SIGNATURE, CSMAGIC_CODEDIRECTORY = 0xFADE0CC0, 0xFADE0C02
CS_ADHOC = 0x2
HASHES = {1: hashlib.sha1, 2: hashlib.sha256}
ALLOWED_LIBRARIES = {"/usr/lib/libSystem.B.dylib"}


def version(word):
    return f"{word >> 16}.{(word >> 8) & 0xFF}"


def load_commands(data):
    """(command, offset of its body's start) for each load command."""
    magic, _, _, _, ncmds, _, _, _ = struct.unpack_from("<IiiIIIII", data, 0)
    if magic != MH_MAGIC_64:
        raise SystemExit("not a 64-bit Mach-O file")
    offset = 32
    for _ in range(ncmds):
        cmd, size = struct.unpack_from("<II", data, offset)
        yield cmd, offset
        offset += size


def signature_problem(data, dataoff, datasize):
    """None if the code directory's page hashes match the file, else what is wrong."""
    blob = data[dataoff : dataoff + datasize]
    magic, _, count = struct.unpack_from(">III", blob, 0)
    if magic != CSMAGIC_EMBEDDED_SIGNATURE:
        return "no embedded signature blob"
    for i in range(count):
        _, offset = struct.unpack_from(">II", blob, 12 + 8 * i)
        if struct.unpack_from(">I", blob, offset)[0] != CSMAGIC_CODEDIRECTORY:
            continue
        fields = struct.unpack_from(">IIIIIIIIIBBBB", blob, offset)
        flags, hash_offset, n_code, code_limit = fields[3], fields[4], fields[7], fields[8]
        hash_size, hash_type, page_log2 = fields[9], fields[10], fields[12]
        if not flags & CS_ADHOC:
            return "the code directory is not ad-hoc signed"
        page = 1 << page_log2
        for slot in range(n_code):
            start = slot * page
            digest = HASHES[hash_type](data[start : min(start + page, code_limit)]).digest()
            at = offset + hash_offset + slot * hash_size
            if digest[:hash_size] != blob[at : at + hash_size]:
                return f"page {slot}'s hash does not match the file"
        return None
    return "no code directory"


def check(path, min_os, signed):
    with open(path, "rb") as f:
        data = f.read()
    minimum, libraries, problems, signature = None, [], [], None
    for cmd, at in load_commands(data):
        if cmd == LC_BUILD_VERSION:
            minimum = version(struct.unpack_from("<IIIII", data, at)[3])
        elif cmd == LC_VERSION_MIN_MACOSX:
            minimum = version(struct.unpack_from("<IIII", data, at)[2])
        elif cmd in (LC_LOAD_DYLIB, LC_LOAD_WEAK_DYLIB, LC_REEXPORT_DYLIB):
            name_offset = struct.unpack_from("<I", data, at + 8)[0]
            libraries.append(data[at + name_offset :].split(b"\0", 1)[0].decode())
        elif cmd == LC_CODE_SIGNATURE:
            signature = struct.unpack_from("<II", data, at + 8)
    if minimum != min_os:
        problems.append(f"minimum macOS {minimum}, expected {min_os}")
    if set(libraries) - ALLOWED_LIBRARIES or not libraries:
        problems.append(f"links {libraries}, expected only {sorted(ALLOWED_LIBRARIES)}")
    if signed:
        why = signature_problem(data, *signature) if signature else "no LC_CODE_SIGNATURE"
        if why:
            problems.append(f"code signature: {why}")
    sign_note = ", ad-hoc signature intact" if signed else ""
    return problems, f"macOS {minimum}+, links {', '.join(libraries)}{sign_note}"


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("module")
    parser.add_argument("--min-os", required=True)
    parser.add_argument("--signed", action="store_true")
    args = parser.parse_args(argv)
    problems, summary = check(args.module, args.min_os, args.signed)
    if problems:
        sys.exit(f"{args.module}: " + "; ".join(problems))
    print(f"{args.module}: {summary}")


if __name__ == "__main__":
    main()
