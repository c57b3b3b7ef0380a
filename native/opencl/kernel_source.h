// SPDX-License-Identifier: GPL-3.0-or-later
// The OpenCL C source of every kernel, embedded at build time (cmake/embed_kernels.cmake):
// no file is looked up at run time.
#pragma once

namespace sdf::cl {

const char* kernel_source();

}  // namespace sdf::cl
