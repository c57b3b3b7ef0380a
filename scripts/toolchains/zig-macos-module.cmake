# SPDX-License-Identifier: GPL-3.0-or-later
# Loaded after CMake's Darwin platform rules (CMAKE_USER_MAKE_RULES_OVERRIDE, set in zig.cmake).
# zig's Mach-O linker (0.15.2) crashes linking a bundle (-bundle, CMake's MODULE libraries, as
# pybind11 makes): the module is linked as a dylib instead, which Python's import (dlopen)
# loads the same way.
set(CMAKE_SHARED_MODULE_CREATE_CXX_FLAGS "-shared -Wl,-headerpad_max_install_names")
