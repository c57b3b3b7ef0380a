// SPDX-License-Identifier: GPL-3.0-or-later
// The pipeline's options from the names the Python layer passes (checked there already; a
// name unknown here is a ValueError all the same).
#pragma once

#include <stdexcept>
#include <string>

#include "pipeline/sdf.h"
#include "post/normalize.h"

namespace sdf {

inline Sampling parse_sampling(const std::string& name) {
  if (name == "fibonacci") return Sampling::Fibonacci;
  if (name == "random") return Sampling::Random;
  if (name == "cgal") return Sampling::Cgal;
  throw std::invalid_argument("sampling must be 'fibonacci', 'random' or 'cgal', got '" + name +
                              "'");
}

inline PointKind parse_points(const std::string& name) {
  if (name == "faces") return PointKind::Faces;
  if (name == "vertices") return PointKind::Vertices;
  throw std::invalid_argument("points must be 'faces' or 'vertices', got '" + name + "'");
}

inline BvhQuality parse_bvh_quality(const std::string& name) {
  if (name == "auto") return BvhQuality::Auto;
  if (name == "high") return BvhQuality::High;
  if (name == "fast") return BvhQuality::Fast;
  throw std::invalid_argument("bvh_quality must be 'auto', 'high' or 'fast', got '" + name + "'");
}

inline Orientation parse_orientation(const std::string& name) {
  if (name == "auto") return Orientation::Auto;
  if (name == "as_is") return Orientation::AsIs;
  if (name == "flip") return Orientation::Flip;
  throw std::invalid_argument("orientation must be 'auto', 'as_is' or 'flip', got '" + name + "'");
}

inline Accel parse_accel(const std::string& name) {
  if (name == "bvh") return Accel::Bvh;
  if (name == "octree") return Accel::Octree;
  throw std::invalid_argument("accel must be 'bvh' or 'octree', got '" + name + "'");
}

inline Normalization parse_normalization(const std::string& name) {
  if (name == "linear") return Normalization::Linear;
  if (name == "log") return Normalization::Log;
  throw std::invalid_argument("normalize must be 'linear' or 'log', got '" + name + "'");
}

inline const char* fill_name(FillResult r) {
  switch (r) {
    case FillResult::NothingToFill: return "none";
    case FillResult::Filled: return "filled";
    case FillResult::NoValueAnywhere: return "no-value-anywhere";
  }
  return "?";
}

}  // namespace sdf
