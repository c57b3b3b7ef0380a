// SPDX-License-Identifier: GPL-3.0-or-later
// libFuzzer target for the compute entry point: arbitrary bytes become a vertex array, a
// triangle index array and options, which go through sdf::make_mesh and sdf::compute on the
// CPU engine, as the Python module passes them (bindings/module.cpp).
//
// The contract checked, beyond "no crash, no sanitizer report":
// * the only exceptions are the documented clean refusals: std::invalid_argument (bad mesh or
//   options, make_mesh and make_cone), std::length_error (an octree past its 24-bit pointers)
//   and sdf::Cancelled when the progress callback asked to stop;
// * a computation that returns has one value per point, every raw value finite and >= 0, and
//   valid_rays in [0, rays] (all raw values 0 when the result says no point had a value);
// * or it stopped at faces with reversed twins, each after its twin, at its twin's positions
//   wound the other way; the mesh without them, cast again, keeps the contract above.
// Anything else calls abort(), which libFuzzer reports as a crash with the input saved.
//
// Input layout (little-endian; every byte string is a valid input, short ones are padded
// with zeros):
//   0      rays = 1 + b % 64
//   1      cone angle: 0..7 specials (0, 180, NaN, 1e-6, 179.99999, -30, inf, 1e-300),
//          otherwise (b - 7.5) * 180 / 248, inside (0, 180)
//   2      bits 0-1 sampling (fibonacci, random, cgal, fibonacci); bit 2 points = vertices;
//          bit 3 accel = octree; bit 4 two threads; bits 5-7 octree max_depth 0..7
//   3      bits 0-3 octree leaf_size 1..16; bits 4-6 cancel at that progress call (0 never);
//          bit 7 orientation as_is (seed even) or flip (seed odd), else auto
//   4-7    seed
//   8      scale of grid coordinates: 2^(int8)b
//   9      offset added to grid coordinates: 0, or 2^(int8)b when b != 0
//   10-11  vertex count, at most kMaxVertices (fewer if the input ends first)
//   then   the coordinates, each a tag byte: < 0xF0 a grid value (tag - 120) / 8 * scale +
//          offset; 0xF0.. specials (NaN, +-inf, +-1e300, 3.5e38, 4.9e-324, 1e-40, -0, 1e-30,
//          1e30); 0xFB a float32 follows; 0xFF a double follows
//   then   triangles until the input ends (at most kMaxTriangles), each corner an uint16:
//          < 0xFFF0 that value modulo the vertex count; 0xFFF0.. specials (-1, vertex count,
//          INT64_MIN, INT64_MAX, 2^32, 2^32 + 1); 0xFFF6 an int64 follows; others as they are.
//
// tests/fuzz/make_corpus.py writes real meshes in this layout (the seed corpus).
// SDF_FUZZ_DESCRIBE=1 in the environment prints the decoded input and its outcome.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "pipeline/sdf.h"

namespace {

constexpr std::size_t kMaxVertices = 2048;
constexpr std::size_t kMaxTriangles = 4096;

class Reader {
 public:
  Reader(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}
  bool empty() const { return pos_ >= size_; }
  std::size_t left() const { return pos_ < size_ ? size_ - pos_ : 0; }
  template <class T>
  T take() {  // zero-padded past the end
    T value{};
    unsigned char bytes[sizeof(T)] = {};
    for (std::size_t i = 0; i < sizeof(T) && pos_ < size_; ++i) bytes[i] = data_[pos_++];
    std::memcpy(&value, bytes, sizeof(T));
    return value;
  }

 private:
  const std::uint8_t* data_;
  std::size_t size_, pos_ = 0;
};

[[noreturn]] void fail(const char* what, const char* detail = "") {
  std::fprintf(stderr, "compute_fuzzer: contract broken: %s %s\n", what, detail);
  std::fflush(stderr);
  std::abort();
}

double cone_angle(std::uint8_t b) {
  switch (b) {
    case 0: return 0.0;
    case 1: return 180.0;
    case 2: return std::numeric_limits<double>::quiet_NaN();
    case 3: return 1e-6;
    case 4: return 179.99999;
    case 5: return -30.0;
    case 6: return std::numeric_limits<double>::infinity();
    case 7: return 1e-300;
    default: return (b - 7.5) * 180.0 / 248.0;
  }
}

double coordinate(Reader& in, double scale, double offset) {
  const std::uint8_t tag = in.take<std::uint8_t>();
  if (tag < 0xF0) return (tag - 120) / 8.0 * scale + offset;
  switch (tag) {
    case 0xF0: return std::numeric_limits<double>::quiet_NaN();
    case 0xF1: return std::numeric_limits<double>::infinity();
    case 0xF2: return -std::numeric_limits<double>::infinity();
    case 0xF3: return 1e300;
    case 0xF4: return -1e300;
    case 0xF5: return 3.5e38;    // just past the largest float
    case 0xF6: return 4.9e-324;  // the smallest double denormal
    case 0xF7: return 1e-40;     // a float denormal
    case 0xF8: return -0.0;
    case 0xF9: return 1e-30;
    case 0xFA: return 1e30;
    case 0xFB: return static_cast<double>(in.take<float>());
    default: return in.take<double>();
  }
}

std::int64_t index(Reader& in, std::size_t vertex_count) {
  const std::uint16_t v = in.take<std::uint16_t>();
  const auto n = static_cast<std::int64_t>(vertex_count);
  if (v < 0xFFF0) return n > 0 ? v % n : v;
  switch (v) {
    case 0xFFF0: return -1;
    case 0xFFF1: return n;
    case 0xFFF2: return std::numeric_limits<std::int64_t>::min();
    case 0xFFF3: return std::numeric_limits<std::int64_t>::max();
    case 0xFFF4: return std::int64_t{1} << 32;
    case 0xFFF5: return (std::int64_t{1} << 32) + 1;
    case 0xFFF6: return in.take<std::int64_t>();
    default: return v;
  }
}

// SDF_FUZZ_DESCRIBE=1: prints the decoded input (for reports and regression tests).
void describe(const sdf::Options& o, int cancel_at, const std::vector<double>& vertices,
              const std::vector<std::int64_t>& triangles) {
  static const char* const samplings[] = {"fibonacci", "random", "cgal"};
  std::fprintf(stderr,
               "rays=%d cone_angle=%.17g sampling=%s seed=%u points=%s accel=%s threads=%u "
               "octree.max_depth=%d octree.leaf_size=%d cancel_at=%d orientation=%s\n",
               o.rays, o.cone_angle, samplings[static_cast<int>(o.sampling)], o.seed,
               o.points == sdf::PointKind::Faces ? "faces" : "vertices",
               o.accel == sdf::Accel::Bvh ? "bvh" : "octree", o.threads, o.octree.max_depth,
               o.octree.leaf_size, cancel_at,
               o.orientation == sdf::Orientation::Auto   ? "auto"
               : o.orientation == sdf::Orientation::AsIs ? "as_is"
                                                         : "flip");
  std::fprintf(stderr, "vertices (%zu):\n", vertices.size() / 3);
  for (std::size_t i = 0; i < vertices.size(); i += 3)
    std::fprintf(stderr, "  %.17g %.17g %.17g\n", vertices[i], vertices[i + 1], vertices[i + 2]);
  std::fprintf(stderr, "triangles (%zu):\n", triangles.size() / 3);
  for (std::size_t i = 0; i < triangles.size(); i += 3)
    std::fprintf(stderr, "  %lld %lld %lld\n", static_cast<long long>(triangles[i]),
                 static_cast<long long>(triangles[i + 1]),
                 static_cast<long long>(triangles[i + 2]));
}

}  // namespace

void check_twins(const sdf::Mesh& mesh, const sdf::ReversedTwins& twins) {
  if (twins.twin.size() != twins.dropped.size() || twins.corner.size() != twins.dropped.size())
    fail("twins' arrays differ in length");
  for (std::size_t i = 0; i < twins.dropped.size(); ++i) {
    const std::uint32_t face = twins.dropped[i], twin = twins.twin[i];
    if (face >= mesh.triangles.size() || twin >= face) fail("a twin is not an earlier face");
    if (i > 0 && face <= twins.dropped[i - 1]) fail("faces left out are not increasing");
    if (twins.corner[i] > 2) fail("a twin's corner is not 0, 1 or 2");
    for (int k = 0; k < 3; ++k)
      if (mesh.vertices[mesh.triangles[face][k]] !=
          mesh.vertices[mesh.triangles[twin][(twins.corner[i] + 3 - k) % 3]])
        fail("a face left out is not at its twin's positions, wound the other way");
  }
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Reader in(data, size);
  sdf::Options options;
  options.engine = "cpu";
  options.rays = 1 + in.take<std::uint8_t>() % 64;
  options.cone_angle = cone_angle(in.take<std::uint8_t>());
  const std::uint8_t flags = in.take<std::uint8_t>();
  options.sampling = static_cast<sdf::Sampling>((flags & 3) == 3 ? 0 : flags & 3);
  options.points = flags & 4 ? sdf::PointKind::Vertices : sdf::PointKind::Faces;
  options.accel = flags & 8 ? sdf::Accel::Octree : sdf::Accel::Bvh;
  options.threads = flags & 16 ? 2 : 1;
  options.octree.max_depth = flags >> 5;
  const std::uint8_t more = in.take<std::uint8_t>();
  options.octree.leaf_size = 1 + (more & 15);
  const int cancel_at = (more >> 4) & 7;
  options.seed = in.take<std::uint32_t>();
  if (more & 128)
    options.orientation = options.seed & 1 ? sdf::Orientation::Flip : sdf::Orientation::AsIs;
  const double scale = std::ldexp(1.0, in.take<std::int8_t>());
  const std::int8_t offset_exponent = in.take<std::int8_t>();
  const double offset = offset_exponent == 0 ? 0.0 : std::ldexp(1.0, offset_exponent);
  const std::size_t wanted_vertices = in.take<std::uint16_t>() % (kMaxVertices + 1);

  std::vector<double> vertices;
  for (std::size_t i = 0; i < 3 * wanted_vertices && !in.empty(); ++i)
    vertices.push_back(coordinate(in, scale, offset));
  vertices.resize(vertices.size() / 3 * 3);
  const std::size_t vertex_count = vertices.size() / 3;
  std::vector<std::int64_t> triangles;
  while (!in.empty() && triangles.size() < 3 * kMaxTriangles)
    triangles.push_back(index(in, vertex_count));
  triangles.resize(triangles.size() / 3 * 3);
  const std::size_t triangle_count = triangles.size() / 3;

  const bool verbose = std::getenv("SDF_FUZZ_DESCRIBE") != nullptr;
  if (verbose) describe(options, cancel_at, vertices, triangles);
  const auto outcome = [verbose](const char* what, const char* detail = "") {
    if (verbose) std::fprintf(stderr, "outcome: %s %s\n", what, detail);
    return 0;
  };

  sdf::Mesh mesh;
  try {
    mesh = sdf::make_mesh(vertices.data(), vertex_count, triangles.data(), triangle_count);
  } catch (const std::invalid_argument& e) {
    return outcome("make_mesh refused:", e.what());
  } catch (const std::exception& e) {
    fail("make_mesh threw something other than std::invalid_argument:", e.what());
  }

  int calls = 0;
  const sdf::ProgressFn progress = [&](double fraction) {
    if (!(fraction >= 0.0 && fraction <= 1.0)) fail("progress outside [0, 1]");
    return cancel_at == 0 || ++calls < cancel_at;
  };
  // compute() on the mesh `make` gives, the only exceptions the documented ones: false when it
  // ended the run cleanly (a refusal, or the cancel asked for), which `outcome` has told.
  sdf::Output out;
  auto computed = [&](const std::string& call, auto&& make) {
    try {
      out = sdf::compute(make(), options, progress);
      return true;
    } catch (const std::invalid_argument& e) {
      outcome((call + " refused:").c_str(), e.what());
    } catch (const std::length_error& e) {
      outcome((call + " refused:").c_str(), e.what());
    } catch (const sdf::Cancelled&) {
      if (cancel_at == 0) fail("Cancelled without a cancel request");
      outcome("cancelled");
    } catch (const std::exception& e) {
      fail((call + " threw something other than a documented error:").c_str(), e.what());
    }
    return false;
  };
  if (!computed("compute", [&] { return mesh; })) return 0;

  std::size_t triangle_count_cast = triangle_count;
  if (!out.twins.empty()) {
    check_twins(mesh, out.twins);
    // What the caller does (api.py): the mesh cast again without the faces left out.
    std::vector<std::int64_t> kept;
    std::size_t next = 0;
    for (std::size_t f = 0; f < triangle_count; ++f) {
      if (next < out.twins.dropped.size() && out.twins.dropped[next] == f) {
        ++next;
        continue;
      }
      kept.insert(kept.end(), triangles.begin() + 3 * f, triangles.begin() + 3 * f + 3);
    }
    triangle_count_cast = kept.size() / 3;
    options.find_twins = false;
    calls = 0;
    if (!computed("compute without twins", [&] {
          return sdf::make_mesh(vertices.data(), vertex_count, kept.data(), triangle_count_cast);
        }))
      return 0;
    if (!out.twins.empty()) fail("twins reported with find_twins off");
  }
  const std::size_t points =
      options.points == sdf::PointKind::Faces ? triangle_count_cast : vertex_count;
  if (out.raw.size() != points || out.valid_rays.size() != points)
    fail("output size is not the point count");
  if (out.orientation.flipped_faces > triangle_count_cast)
    fail("more faces flipped than there are");
  if ((options.orientation == sdf::Orientation::AsIs && out.orientation.flipped_faces != 0) ||
      (options.orientation == sdf::Orientation::Flip &&
       out.orientation.flipped_faces != triangle_count_cast))
    fail("flipped_faces does not match the orientation asked for");
  for (std::size_t i = 0; i < points; ++i) {
    if (!std::isfinite(out.raw[i])) fail("a raw value is not finite");
    if (out.raw[i] < 0.0f) fail("a raw value is negative");
    if (out.valid_rays[i] < 0 || out.valid_rays[i] > options.rays)
      fail("valid_rays outside [0, rays]");
    if (out.fill == sdf::FillResult::NoValueAnywhere && out.raw[i] != 0.0f)
      fail("no value anywhere, yet a raw value is not 0");
  }
  if (verbose) {
    std::fprintf(stderr, "outcome: computed (%s), raw:", out.engine.c_str());
    for (std::size_t i = 0; i < points && i < 16; ++i) std::fprintf(stderr, " %g", out.raw[i]);
    std::fprintf(stderr, "%s\n", points > 16 ? " ..." : "");
  }
  return 0;
}
