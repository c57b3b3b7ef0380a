// SPDX-License-Identifier: GPL-3.0-or-later
// The random numbers CGAL's k-means seeding draws, reproduced bit for bit, so that
// mode "cgal" picks the same initial centres as CGAL's segmentation: a 48-bit linear
// congruential generator (POSIX drand48's constants, 31-bit outputs) seeded as
// (seed << 16) | 0x330e, integers in [0, n) by bucketing with rejection, reals by scaling
// output / 2^31. CGAL's Random draws one integer when it is constructed; so does this.
#pragma once

#include <cstddef>
#include <cstdint>

namespace sdf::segment {

class CgalRandom {
 public:
  explicit CgalRandom(std::uint32_t seed) : state_((std::uint64_t{seed} << 16 | 0x330e) & kMask) {
    uniform_index(1u << 15);  // CGAL's Random fills a 15-bit value at construction
  }

  // An integer in [0, n), n >= 1 and n <= 2^31.
  std::size_t uniform_index(std::size_t n) {
    if (n <= 1) return 0;
    const std::uint64_t range = n - 1;
    const std::uint64_t bucket = (kMaxOutput + std::uint64_t{1}) / (range + 1);
    for (;;) {
      const std::uint64_t r = next() / bucket;
      if (r <= range) return static_cast<std::size_t>(r);
    }
  }

  // A real in [lower, upper).
  double uniform_real(double lower, double upper) {
    for (;;) {
      const double x =
          static_cast<double>(next()) / (static_cast<double>(kMaxOutput) + 1.0) * (upper - lower) +
          lower;
      if (x < upper) return x;
    }
  }

 private:
  static constexpr std::uint64_t kMask = (std::uint64_t{1} << 48) - 1;
  static constexpr std::uint64_t kMaxOutput = 0x7FFFFFFF;

  std::uint32_t next() {
    state_ = (0x5DEECE66Dull * state_ + 0xB) & kMask;
    return static_cast<std::uint32_t>(state_ >> 17);
  }

  std::uint64_t state_;
};

}  // namespace sdf::segment
