# SPDX-License-Identifier: GPL-3.0-or-later
# macos-x64 with zig: macOS 10.15 and later; Python's symbols are resolved when the interpreter loads the module.
set(CMAKE_SYSTEM_NAME Darwin)
set(CMAKE_SYSTEM_PROCESSOR x86_64)
set(SDF_ZIG_TARGET x86_64-macos.10.15)
include(${CMAKE_CURRENT_LIST_DIR}/zig.cmake)
