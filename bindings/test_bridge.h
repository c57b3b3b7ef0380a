// SPDX-License-Identifier: GPL-3.0-or-later
// What the test-only module shape_diameter._testing reaches in _core. Each extension module
// links its own copy of the core, so each has its own test overrides and its own OpenCL
// state; _core hands out this record (a capsule, _core._test_bridge) so that the overrides
// _testing sets reach the computations _core runs, and _testing can read _core's program
// counts. Both modules are built from one tree in one build: the record's layout is theirs.
// Functions, not a pointer to _core's overrides: _core's own code copies the strings, so each
// module frees only what its own allocator gave.
#pragma once

#include <cstdint>

#include "util/test_overrides.h"

namespace sdf {

struct TestBridge {
  // Sets _core's copy of the overrides to `overrides`.
  void (*set_overrides)(const TestOverrides& overrides);
  // Programs _core's OpenCL engine built from source and loaded from the cache so far in the
  // process (zeros in a build without OpenCL). Throws nothing.
  void (*program_stats)(std::uint64_t* compiled, std::uint64_t* from_cache);
};

// The capsule's name, checked on both sides.
inline constexpr const char* kTestBridgeName = "shape_diameter._core._test_bridge";

}  // namespace sdf
