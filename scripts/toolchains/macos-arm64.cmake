# SPDX-License-Identifier: GPL-3.0-or-later
# macos-arm64 with zig: macOS 11 and later (the first on Apple Silicon); Python's symbols are resolved when the interpreter loads the module.
set(CMAKE_SYSTEM_NAME Darwin)
set(CMAKE_SYSTEM_PROCESSOR arm64)
set(SDF_ZIG_TARGET aarch64-macos.11.0)
include(${CMAKE_CURRENT_LIST_DIR}/zig.cmake)
