# SPDX-License-Identifier: GPL-3.0-or-later
# Cross-compiling for 64-bit Arm Linux with Debian's g++-aarch64-linux-gnu (scripts/
# cross_aarch64.sh): cmake -DCMAKE_TOOLCHAIN_FILE=cmake/aarch64-linux-gnu.cmake ...
# Programs built here run under qemu-user where it is installed (ctest, and the test
# discovery of gtest_discover_tests, through CMAKE_CROSSCOMPILING_EMULATOR).
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(SDF_AARCH64_SYSROOT /usr/aarch64-linux-gnu)

set(CMAKE_C_COMPILER aarch64-linux-gnu-gcc)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)

# Libraries and CMake packages come from the target's tree only (the host's are x86-64);
# headers may also come from the host's /usr/include, where the arch-independent ones live
# (GLM, the OpenCL headers, GoogleTest's), none of them with compiled parts.
set(CMAKE_FIND_ROOT_PATH ${SDF_AARCH64_SYSROOT})
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE BOTH)

find_program(SDF_QEMU_AARCH64 NAMES qemu-aarch64-static qemu-aarch64)
if(SDF_QEMU_AARCH64)
  set(CMAKE_CROSSCOMPILING_EMULATOR ${SDF_QEMU_AARCH64} -L ${SDF_AARCH64_SYSROOT})
endif()
