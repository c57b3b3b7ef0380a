// SPDX-License-Identifier: GPL-3.0-or-later
#include "test_overrides.h"

namespace sdf {

TestOverrides& test_overrides() {
  static TestOverrides overrides;
  return overrides;
}

}  // namespace sdf
