# SPDX-License-Identifier: GPL-3.0-or-later
# windows-x64 with zig: against the Universal C Runtime (api-ms-win-crt), as CPython itself is, with MinGW-w64's headers.
set(CMAKE_SYSTEM_NAME Windows)
set(CMAKE_SYSTEM_PROCESSOR AMD64)
set(SDF_ZIG_TARGET x86_64-windows-gnu)
include(${CMAKE_CURRENT_LIST_DIR}/zig.cmake)
