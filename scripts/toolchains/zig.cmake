# SPDX-License-Identifier: GPL-3.0-or-later
# Cross-compiling with zig's clang (the `ziglang` package from PyPI, scripts/build_wheels.sh
# installs it): one compiler, with its own libc headers and libc++, for every target the
# wheels are built for. Included by the per-target files beside it, which set SDF_ZIG_TARGET
# (zig's target triple, e.g. x86_64-windows-gnu, x86_64-linux-gnu.2.28) and the CMake
# system name and processor.
#
# The compiler is zig behind small launcher scripts (CMake wants one program per tool), made
# by scripts/build_wheels.sh in $SDF_ZIG_WRAPPERS/<target>/{cc,c++,ar,ranlib}. An environment
# variable, not a cache entry, so that CMake's try_compile projects see it too.
if(NOT DEFINED ENV{SDF_ZIG_WRAPPERS})
  message(FATAL_ERROR "SDF_ZIG_WRAPPERS is not set: build with scripts/build_wheels.sh")
endif()
set(SDF_ZIG_TOOLS "$ENV{SDF_ZIG_WRAPPERS}/${SDF_ZIG_TARGET}")

set(CMAKE_C_COMPILER "${SDF_ZIG_TOOLS}/cc")
set(CMAKE_CXX_COMPILER "${SDF_ZIG_TOOLS}/c++")
set(CMAKE_AR "${SDF_ZIG_TOOLS}/ar" CACHE FILEPATH "" FORCE)
set(CMAKE_RANLIB "${SDF_ZIG_TOOLS}/ranlib" CACHE FILEPATH "" FORCE)

# Nothing is looked up on the host: headers and libraries come from zig, from the folders the
# build names explicitly (Python, GLM, OpenCL headers), never from the host's /usr.
set(CMAKE_FIND_ROOT_PATH "$ENV{SDF_ZIG_WRAPPERS}/no-sysroot")
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)

# macOS: the linker signs the module (ad-hoc, which arm64 macOS requires); a strip after the
# link would void that signature and macOS would refuse to load it. No strip there.
if(CMAKE_SYSTEM_NAME STREQUAL "Darwin")
  set(CMAKE_STRIP "" CACHE FILEPATH "No strip: it would void the code signature" FORCE)
  set(CMAKE_USER_MAKE_RULES_OVERRIDE_CXX "${CMAKE_CURRENT_LIST_DIR}/zig-macos-module.cmake")
endif()
