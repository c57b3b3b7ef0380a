# SPDX-License-Identifier: GPL-3.0-or-later
# windows-arm64 with zig: against the Universal C Runtime (api-ms-win-crt), as CPython itself is, with MinGW-w64's headers.
set(CMAKE_SYSTEM_NAME Windows)
set(CMAKE_SYSTEM_PROCESSOR ARM64)
set(SDF_ZIG_TARGET aarch64-windows-gnu)
include(${CMAKE_CURRENT_LIST_DIR}/zig.cmake)
