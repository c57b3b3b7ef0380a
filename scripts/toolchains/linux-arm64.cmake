# SPDX-License-Identifier: GPL-3.0-or-later
# linux-arm64 with zig: glibc 2.28 and later (manylinux_2_28): zig links against stubs of that glibc's symbols, and links libc++ into the module.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(SDF_ZIG_TARGET aarch64-linux-gnu.2.28)
include(${CMAKE_CURRENT_LIST_DIR}/zig.cmake)
