// SPDX-License-Identifier: GPL-3.0-or-later
// AVX2 and FMA are enabled per function (SDF_AVX2), not for the file: inline functions of the
// headers included here then stay baseline x86-64 wherever the linker keeps their copy.
// Compiled with -ffp-contract=off (CMakeLists.txt): the triangle test must round exactly as
// kern::sdf_intersect_triangle does (no fused multiply-add), while the box test fuses on
// purpose, its boxes being grown to cover rounding (bvh_margin.h).
#include "cast/bvh8_traverse.h"

#if SDF_HAVE_BVH8
#include <immintrin.h>

#define SDF_AVX2 __attribute__((target("avx2,fma")))

namespace sdf {

namespace {

// kern::sdf_intersect_triangle on four triangles at once: the same operations in the same
// order on each lane, so each lane's t, det and verdict are the scalar test's, bit for bit
// (including NaN, which passes every comparison the scalar code writes as a rejection).
// The lanes that pass then go through the scalar update in lane order, which keeps its ties.
SDF_AVX2 inline void intersect_packet(const TrianglePacket4& p, glm::vec3 o, glm::vec3 d,
                                      float tmin, std::int32_t skip_id, kern::SdfHit* hit) {
  const __m128 dx = _mm_set1_ps(d.x), dy = _mm_set1_ps(d.y), dz = _mm_set1_ps(d.z);
  const __m128 e1x = _mm_load_ps(p.e1_x), e1y = _mm_load_ps(p.e1_y), e1z = _mm_load_ps(p.e1_z);
  const __m128 e2x = _mm_load_ps(p.e2_x), e2y = _mm_load_ps(p.e2_y), e2z = _mm_load_ps(p.e2_z);
  // p = cross(d, e2); det = dot(e1, p)
  const __m128 px = _mm_sub_ps(_mm_mul_ps(dy, e2z), _mm_mul_ps(dz, e2y));
  const __m128 py = _mm_sub_ps(_mm_mul_ps(dz, e2x), _mm_mul_ps(dx, e2z));
  const __m128 pz = _mm_sub_ps(_mm_mul_ps(dx, e2y), _mm_mul_ps(dy, e2x));
  const __m128 det =
      _mm_add_ps(_mm_add_ps(_mm_mul_ps(e1x, px), _mm_mul_ps(e1y, py)), _mm_mul_ps(e1z, pz));
  const __m128 inv_det = _mm_div_ps(_mm_set1_ps(1.0f), det);
  // s = o - v0; u = dot(s, p) * inv_det
  const __m128 sx = _mm_sub_ps(_mm_set1_ps(o.x), _mm_load_ps(p.v0_x));
  const __m128 sy = _mm_sub_ps(_mm_set1_ps(o.y), _mm_load_ps(p.v0_y));
  const __m128 sz = _mm_sub_ps(_mm_set1_ps(o.z), _mm_load_ps(p.v0_z));
  const __m128 u = _mm_mul_ps(
      _mm_add_ps(_mm_add_ps(_mm_mul_ps(sx, px), _mm_mul_ps(sy, py)), _mm_mul_ps(sz, pz)), inv_det);
  // q = cross(s, e1); v = dot(d, q) * inv_det; t = dot(e2, q) * inv_det
  const __m128 qx = _mm_sub_ps(_mm_mul_ps(sy, e1z), _mm_mul_ps(sz, e1y));
  const __m128 qy = _mm_sub_ps(_mm_mul_ps(sz, e1x), _mm_mul_ps(sx, e1z));
  const __m128 qz = _mm_sub_ps(_mm_mul_ps(sx, e1y), _mm_mul_ps(sy, e1x));
  const __m128 v = _mm_mul_ps(
      _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, qx), _mm_mul_ps(dy, qy)), _mm_mul_ps(dz, qz)), inv_det);
  const __m128 t = _mm_mul_ps(
      _mm_add_ps(_mm_add_ps(_mm_mul_ps(e2x, qx), _mm_mul_ps(e2y, qy)), _mm_mul_ps(e2z, qz)),
      inv_det);
  const __m128 lo = _mm_set1_ps(-SDF_BARYCENTRIC_SLACK);
  const __m128 hi = _mm_set1_ps(1.0f + SDF_BARYCENTRIC_SLACK);
  // Rejections exactly as the scalar code writes them (ordered comparisons: false on NaN,
  // except "not greater than tmin", true on NaN, so a NaN t is turned away as there).
  __m128 reject = _mm_cmpeq_ps(det, _mm_setzero_ps());
  reject = _mm_or_ps(reject, _mm_or_ps(_mm_cmplt_ps(u, lo), _mm_cmpgt_ps(u, hi)));
  reject = _mm_or_ps(reject, _mm_or_ps(_mm_cmplt_ps(v, lo), _mm_cmpgt_ps(_mm_add_ps(u, v), hi)));
  reject = _mm_or_ps(
      reject, _mm_or_ps(_mm_cmpngt_ps(t, _mm_set1_ps(tmin)), _mm_cmpgt_ps(t, _mm_set1_ps(hit->t))));
  reject = _mm_or_ps(reject, _mm_castsi128_ps(_mm_cmpeq_epi32(
                                 _mm_load_si128(reinterpret_cast<const __m128i*>(p.id)),
                                 _mm_set1_epi32(skip_id))));
  int pass = ~_mm_movemask_ps(reject) & 0xF;
  if (pass == 0) return;
  alignas(16) float t_lane[4], det_lane[4];
  _mm_store_ps(t_lane, t);
  _mm_store_ps(det_lane, det);
  while (pass) {
    const int i = __builtin_ctz(pass);
    pass &= pass - 1;
    const float ti = t_lane[i];
    if (ti > hit->t || (ti == hit->t && p.id[i] >= hit->id)) continue;
    hit->t = ti;
    hit->det = det_lane[i];
    hit->id = p.id[i];
  }
}

// One slab distance for eight boxes: the node's plane at `offset` (lo or hi of an axis).
SDF_AVX2 inline __m256 slab(const char* node, std::size_t offset, __m256 inv, __m256 o_inv) {
  return _mm256_fmsub_ps(_mm256_load_ps(reinterpret_cast<const float*>(node + offset)), inv, o_inv);
}

struct Entry {
  std::int32_t child, count;
  float t;
};

// Starts loading what `e` points to: the box pushed nearest is most often the next visit
// after the current one, so its cache misses overlap the current node's work.
inline void prefetch(const Bvh8& bvh, const Entry& e) {
  const char* p = e.child >= 0 ? reinterpret_cast<const char*>(&bvh.nodes[e.child])
                               : reinterpret_cast<const char*>(&bvh.packets[~e.child]);
  for (int line = 0; line < 4; ++line) _mm_prefetch(p + 64 * line, _MM_HINT_T0);
}

// One ray's traversal as a state machine: step() does one visit (a node or a leaf), so that
// two rays can take turns and the cache misses of one overlap the work of the other.
class Ray {
 public:
  SDF_AVX2 Ray(const Bvh8& bvh, glm::vec3 o, glm::vec3 d, float tmin, std::int32_t skip_id)
      : bvh_(bvh), o_(o), d_(d), tmin_(tmin), skip_id_(skip_id) {
    const glm::vec3 inv = kern::sdf_safe_inverse(d, o);
    // Per axis, the plane a ray meets first is lo when it travels up the axis, hi otherwise:
    // chosen once per ray as an offset into the node (empty slots then give near > far).
    constexpr std::size_t kLoX = offsetof(Bvh8Node, lo_x), kHiX = offsetof(Bvh8Node, hi_x);
    constexpr std::size_t kLoY = offsetof(Bvh8Node, lo_y), kHiY = offsetof(Bvh8Node, hi_y);
    constexpr std::size_t kLoZ = offsetof(Bvh8Node, lo_z), kHiZ = offsetof(Bvh8Node, hi_z);
    near_x_ = inv.x < 0.0f ? kHiX : kLoX;
    far_x_ = inv.x < 0.0f ? kLoX : kHiX;
    near_y_ = inv.y < 0.0f ? kHiY : kLoY;
    far_y_ = inv.y < 0.0f ? kLoY : kHiY;
    near_z_ = inv.z < 0.0f ? kHiZ : kLoZ;
    far_z_ = inv.z < 0.0f ? kLoZ : kHiZ;
    inv_x_ = _mm256_set1_ps(inv.x);
    inv_y_ = _mm256_set1_ps(inv.y);
    inv_z_ = _mm256_set1_ps(inv.z);
    o_inv_x_ = _mm256_set1_ps(o.x * inv.x);
    o_inv_y_ = _mm256_set1_ps(o.y * inv.y);
    o_inv_z_ = _mm256_set1_ps(o.z * inv.z);
  }

  const kern::SdfHit& hit() const { return hit_; }

  // One visit; false once the ray is done.
  SDF_AVX2 inline __attribute__((always_inline)) bool step() {
    if (cur_.child < 0) {
      const TrianglePacket4* packet = &bvh_.packets[~cur_.child];
      for (std::int32_t k = 0; k < cur_.count; ++k)
        intersect_packet(packet[k], o_, d_, tmin_, skip_id_, &hit_);
    } else if (visit_node()) {
      return true;
    }
    // Next: the nearest pushed box that may still hold a nearer hit (equal may hold a tie
    // won by a smaller id).
    do {
      if (sp_ == 0) return false;
      cur_ = stack_[--sp_];
    } while (cur_.t > hit_.t);
    return true;
  }

 private:
  // Tests the eight boxes of node cur_; false when none is hit. Otherwise the nearest box hit
  // becomes cur_ and the others are pushed farthest first, so the nearest of them pops first.
  SDF_AVX2 inline __attribute__((always_inline)) bool visit_node() {
    const char* n = reinterpret_cast<const char*>(&bvh_.nodes[cur_.child]);
    const __m256 t_near = _mm256_max_ps(
        _mm256_max_ps(slab(n, near_x_, inv_x_, o_inv_x_), slab(n, near_y_, inv_y_, o_inv_y_)),
        _mm256_max_ps(slab(n, near_z_, inv_z_, o_inv_z_), _mm256_setzero_ps()));
    const __m256 t_far = _mm256_min_ps(
        _mm256_min_ps(slab(n, far_x_, inv_x_, o_inv_x_), slab(n, far_y_, inv_y_, o_inv_y_)),
        _mm256_min_ps(slab(n, far_z_, inv_z_, o_inv_z_), _mm256_set1_ps(hit_.t)));
    unsigned mask = _mm256_movemask_ps(_mm256_cmp_ps(t_near, t_far, _CMP_LE_OQ));
    if (mask == 0) return false;
    const Bvh8Node& node = *reinterpret_cast<const Bvh8Node*>(n);
    alignas(32) float entry[8];
    _mm256_store_ps(entry, t_near);
    // One or two boxes hit are 70% of visits (measured on bunny00 and armadillo-x4): they
    // skip the sort.
    const int a = __builtin_ctz(mask);
    mask &= mask - 1;
    const Entry first{node.child[a], node.count[a], entry[a]};
    if (mask == 0) {
      cur_ = first;
      return true;
    }
    const int b = __builtin_ctz(mask);
    mask &= mask - 1;
    const Entry second{node.child[b], node.count[b], entry[b]};
    if (mask == 0) {
      const bool second_nearer = second.t < first.t;
      stack_[sp_++] = second_nearer ? first : second;
      cur_ = second_nearer ? second : first;
      prefetch(bvh_, stack_[sp_ - 1]);
      return true;
    }
    Entry hits[8] = {first};
    int h = 1;
    auto insert = [&](const Entry& c) {
      int j = h++;
      while (j > 0 && hits[j - 1].t < c.t) {
        hits[j] = hits[j - 1];
        --j;
      }
      hits[j] = c;
    };
    insert(second);
    while (mask) {
      const int i = __builtin_ctz(mask);
      mask &= mask - 1;
      insert(Entry{node.child[i], node.count[i], entry[i]});
    }
    for (int i = 0; i < h - 1; ++i) stack_[sp_++] = hits[i];
    cur_ = hits[h - 1];
    prefetch(bvh_, stack_[sp_ - 1]);
    return true;
  }

  __m256 inv_x_, inv_y_, inv_z_, o_inv_x_, o_inv_y_, o_inv_z_;
  const Bvh8& bvh_;
  glm::vec3 o_, d_;
  float tmin_;
  std::int32_t skip_id_;
  std::size_t near_x_, far_x_, near_y_, far_y_, near_z_, far_z_;
  kern::SdfHit hit_{INFINITY, 0.0f, -1};
  Entry cur_{0, 0, 0.0f};
  int sp_ = 0;
  // Each visit pushes at most 7 more than it pops; the tree is at most ~60 levels deep.
  Entry stack_[512];
};

}  // namespace

SDF_AVX2 kern::SdfHit bvh8_closest_hit_avx2(const Bvh8& bvh, glm::vec3 o, glm::vec3 d, float tmin,
                                            std::int32_t skip_id) {
  if (bvh.empty()) return kern::SdfHit{INFINITY, 0.0f, -1};
  Ray ray(bvh, o, d, tmin, skip_id);
  while (ray.step()) {
  }
  return ray.hit();
}

SDF_AVX2 void bvh8_closest_hits_avx2(const Bvh8& bvh, glm::vec3 o, const glm::vec3* d, int count,
                                     float tmin, std::int32_t skip_id, kern::SdfHit* hits) {
  int r = 0;
  for (; r + 1 < count && !bvh.empty(); r += 2) {
    Ray a(bvh, o, d[r], tmin, skip_id), b(bvh, o, d[r + 1], tmin, skip_id);
    bool a_on = true, b_on = true;
    while (a_on && b_on) {
      a_on = a.step();
      b_on = b.step();
    }
    while (a_on) a_on = a.step();
    while (b_on) b_on = b.step();
    hits[r] = a.hit();
    hits[r + 1] = b.hit();
  }
  for (; r < count; ++r) hits[r] = bvh8_closest_hit_avx2(bvh, o, d[r], tmin, skip_id);
}

}  // namespace sdf

#endif  // SDF_HAVE_BVH8
