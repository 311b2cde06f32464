// A third independent test BVH for `twinray grade`, written the way a performance-minded engineer writes one
// (docs/grading.md, "A third plugin: a 4-wide SIMD BVH"). It shares no code and no arithmetic with
// scotty_bvh.cpp (binary SAH, watertight double test) or lbvh_plugin.c (Karras LBVH, float Moller-Trumbore):
//
//  - build: binned SAH (16 bins over the centroids' box) into a binary tree, the two halves of the top splits
//    built on their own std::threads, then collapsed into a 4-wide tree (each node takes its children's
//    children, largest box first, until it has 4); leaves of 1 to 4 primitives (a range whose centroids all
//    coincide is split at its middle, so coincident boxes never make larger leaves);
//  - traversal: a node's 4 child boxes tested at once with SSE, one child per lane, by the textbook slab test
//    with the precomputed reciprocal direction, near and far planes picked by the direction's sign, no
//    padding; NaN (0 * inf: the origin exactly on a plane the ray runs in) is dropped by the operand order of
//    minps/maxps, so such a plane constrains nothing (the closed box); the hit lanes are sorted by entry
//    distance and pushed farthest first (nearest popped first);
//  - triangles: Baldwin and Weber's test (JCGT 2016, "Fast Ray-Triangle Intersections by Coordinate
//    Transformation"), in float, with the per-triangle affine map to the unit triangle precomputed (in double,
//    stored as float); not watertight, so it does not claim it;
//  - spheres: the closest-approach form in float (Haines et al., Ray Tracing Gems, ch. 7);
//  - claims TWINRAY_PLUGIN_COUNTS_TRAVERSAL (every child box the SIMD test tests counts as a node visited, as
//    the ABI words it and as twinray's binary `bvh` counts, not one per 4-wide node; one primitive per test) and TWINRAY_PLUGIN_HONOURS_TIES: equal computed float t goes to the lower (geom_id, prim_id).
//    Copies of one triangle (same vertices, same order) get the same map, so bit-identical t; a node is
//    pruned only when its entry lies beyond the best t by more than kTieSlack, because a box entered exactly
//    at a hit (a flat, axis-aligned leaf) computes that t with other roundings than the triangle test;
//  - implements intersect_batch and occluded_batch (loops over the rays) and build_stats with sah_cost in the
//    ABI's model, for the 4-wide tree.
//
// Bugs typical of wide SIMD BVHs, one per build (-DBVH4_BUG=n; tests/test_grade_bvh4.cpp):
//   1 EMPTY_SLOT_NAN      empty child slots padded with NaN boxes: the NaN-dropping slab takes them as hit
//                         and the traversal follows the empty slot's reference
//   2 SORT_DROPS_4TH      the hit lanes' sort keeps three: a node whose 4 children are all hit loses the farthest
//   3 SORT_BY_FAR         the hit lanes sorted by exit distance, not entry (only the visiting order changes)
//   4 BATCH_STALE_TMAX    intersect_batch carries the previous ray's closest t over as the next ray's bound
//   5 COLLAPSE_3_LOSES    the collapse, when it opens a child into two with 3 slots filled, writes over the
//                         last slot instead of appending: a grandchild is lost
//   6 ANYHIT_LEAF_BOX     occluded returns 1 as soon as the ray enters a leaf's box
//   7 TIE_T_ONLY          equal t keeps the first hit found (t compared alone, the ids never)
//   8 PRUNE_NO_SLACK      nodes pruned against the best t itself (kTieSlack 0): a flat leaf entered at the
//                         float t of a copy found first, rounded a few ulps later by the slab, is skipped
//   9 RCP_NO_NEWTON       the reciprocal direction by rcpps (12 bits) without the Newton-Raphson step that
//                         makes it a float's (what -ffast-math / -mrecip turn 1.0f / x into): box planes off by
//                         up to 3 parts in 2^13 of their distance
//  10 FTZ_LEFT_SET        build sets MXCSR's flush-to-zero and denormals-are-zero bits "for speed" and leaves
//                         them set: every later float operation of the process (the host's too, in process)
//                         flushes subnormals to zero
//  11 BATCH_WRITES_PAST   occluded_batch answers 4 rays at a time and stores each group's 4 bytes whole, also
//                         for a last group of fewer rays: up to 3 bytes written past the caller's array

#include "twinray_plugin.h"

#include <xmmintrin.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <new>
#include <thread>
#include <vector>

#ifndef BVH4_BUG
#define BVH4_BUG 0
#endif
#define BUG(n) (BVH4_BUG == (n))

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr int kBins = 16;
constexpr std::size_t kMaxLeaf = 4;
// Below this depth the binary build splits by SAH (the deep-tree nest needs about 48); deeper, at the object
// median (at most 29 more levels below 2^29 primitives). A 4-wide level is at least one binary level and
// leaves at most 3 pending entries, which bounds the traversal stack.
constexpr int kSahDepth = 64;
constexpr int kStack = 3 * (kSahDepth + 32) + 4;
// Ranges at least this large are built on their own thread (only the top levels are).
constexpr std::size_t kParallelMin = 16384;
// A node is pruned when its entry lies beyond the best t times (1 + kTieSlack): the slab's t of a plane and
// the triangle test's t of a triangle in that plane round differently (a few ulps), and a tie among copies in
// two flat leaves must still reach the leaf holding the lowest id. 2^-18 is 64 float ulps: it only costs
// visiting a few boxes that end at the hit.
#if BUG(8)
constexpr float kTieSlack = 0.0f;  // "a box entered after the best hit cannot hold a closer one"
#else
constexpr float kTieSlack = 0x1p-18f;
#endif

struct Vec3 {
  float x, y, z;
};
inline Vec3 sub(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline float dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline float get(Vec3 v, int axis) { return axis == 0 ? v.x : (axis == 1 ? v.y : v.z); }

struct Box {
  Vec3 lo{kInf, kInf, kInf}, hi{-kInf, -kInf, -kInf};
  void grow(Vec3 p) {
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  }
  void grow(const Box& b) {
    grow(b.lo);
    grow(b.hi);
  }
  Vec3 centre() const { return {0.5f * (lo.x + hi.x), 0.5f * (lo.y + hi.y), 0.5f * (lo.z + hi.z)}; }
  double area() const {
    if (!(lo.x <= hi.x)) return 0.0;
    const double dx = double(hi.x) - lo.x, dy = double(hi.y) - lo.y, dz = double(hi.z) - lo.z;
    return 2.0 * (dx * dy + dy * dz + dz * dx);
  }
};

// One primitive as the builder sees it.
struct PrimRef {
  Box box;
  Vec3 centre;
  std::uint32_t index;  // into Bvh4::prims_
};

// What a leaf tests: a triangle's Baldwin-Weber map (rows 0, 1: barycentrics u, v; row 2: the plane) and
// normal, or a sphere.
struct Prim {
  float m[3][4];  // triangle: x' = m[r] . (x, 1); sphere: m[0] = centre, radius
  Vec3 ng;
  std::uint32_t geom_id, prim_id;
  bool sphere;
};

// Binary build tree, freed after the collapse.
struct BinNode {
  Box box;
  std::unique_ptr<BinNode> child[2];
  std::uint32_t start = 0, count = 0;  // a leaf's range of PrimRefs
  bool leaf() const { return !child[0]; }
};

// A child reference: a 4-wide node's index, or a leaf (top bit) with its first primitive and count - 1 in
// the low 2 bits.
constexpr std::uint32_t kLeafBit = 0x80000000u;
constexpr std::uint32_t kEmpty = 0xFFFFFFFFu;
inline std::uint32_t leaf_ref(std::uint32_t start, std::uint32_t count) {
  return kLeafBit | (start << 2) | (count - 1);
}

// Four children's boxes in structure-of-arrays order: bounds[0] min x, [1] max x, [2] min y, ... [5] max z.
struct alignas(16) Node4 {
  float bounds[6][4];
  std::uint32_t child[4];
  std::uint32_t children;  // slots in use (2 to 4): the boxes one visit tests
};

struct Ray {
  Vec3 org, dir, inv;
  float tmin, tmax;
  int near_x, near_y, near_z;  // bounds row of the near plane per axis (by the direction's sign)
};

struct Hit {
  float t = kInf, u = 0, v = 0;
  std::uint32_t geom_id = TWINRAY_INVALID_ID, prim_id = TWINRAY_INVALID_ID;
  Vec3 ng{0, 0, 0};
};

Ray make_ray(const twinray_ray& r) {
  Ray ray;
  ray.org = {r.org[0], r.org[1], r.org[2]};
  ray.dir = {r.dir[0], r.dir[1], r.dir[2]};
#if BUG(9)
  {
    alignas(16) float inv[4];
    _mm_store_ps(inv, _mm_rcp_ps(_mm_setr_ps(r.dir[0], r.dir[1], r.dir[2], 1.0f)));  // "fast reciprocal"
    ray.inv = {inv[0], inv[1], inv[2]};
  }
#else
  ray.inv = {1.0f / r.dir[0], 1.0f / r.dir[1], 1.0f / r.dir[2]};  // +-inf for +-0: the slab handles it
#endif
  ray.tmin = r.tmin;
  ray.tmax = r.tmax;
  ray.near_x = std::signbit(r.dir[0]) ? 1 : 0;
  ray.near_y = std::signbit(r.dir[1]) ? 3 : 2;
  ray.near_z = std::signbit(r.dir[2]) ? 5 : 4;
  return ray;
}

// Baldwin-Weber: the affine map taking p0, p1, p2 to (0,0,0), (1,0,0), (0,1,0) and the normal to z, with the
// normal's largest component as the free axis (the paper's three cases). Computed in double, stored as float.
void baldwin_weber(const float* a, const float* b, const float* c, float m[3][4]) {
  const double p0[3] = {a[0], a[1], a[2]}, p1[3] = {b[0], b[1], b[2]}, p2[3] = {c[0], c[1], c[2]};
  const double e1[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
  const double e2[3] = {p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]};
  const double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
  const double c20[3] = {p2[1] * p0[2] - p2[2] * p0[1], p2[2] * p0[0] - p2[0] * p0[2], p2[0] * p0[1] - p2[1] * p0[0]};
  const double c10[3] = {p1[1] * p0[2] - p1[2] * p0[1], p1[2] * p0[0] - p1[0] * p0[2], p1[0] * p0[1] - p1[1] * p0[0]};
  const double np0 = n[0] * p0[0] + n[1] * p0[1] + n[2] * p0[2];
  double r[3][4];
  if (std::fabs(n[0]) > std::fabs(n[1]) && std::fabs(n[0]) > std::fabs(n[2])) {
    const double k = 1.0 / n[0];
    const double rows[3][4] = {{0, e2[2] * k, -e2[1] * k, c20[0] * k},
                               {0, -e1[2] * k, e1[1] * k, -c10[0] * k},
                               {1, n[1] * k, n[2] * k, -np0 * k}};
    std::memcpy(r, rows, sizeof r);
  } else if (std::fabs(n[1]) > std::fabs(n[2])) {
    const double k = 1.0 / n[1];
    const double rows[3][4] = {{-e2[2] * k, 0, e2[0] * k, c20[1] * k},
                               {e1[2] * k, 0, -e1[0] * k, -c10[1] * k},
                               {n[0] * k, 1, n[2] * k, -np0 * k}};
    std::memcpy(r, rows, sizeof r);
  } else {
    const double k = 1.0 / n[2];
    const double rows[3][4] = {{e2[1] * k, -e2[0] * k, 0, c20[2] * k},
                               {-e1[1] * k, e1[0] * k, 0, -c10[2] * k},
                               {n[0] * k, n[1] * k, 1, -np0 * k}};
    std::memcpy(r, rows, sizeof r);
  }
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 4; ++j) m[i][j] = static_cast<float>(r[i][j]);
}

// normalize(cross(p1 - p0, p2 - p0)), precomputed in double: in float, |n|^2 is a product of four coordinate
// differences and leaves float range for edges below about 2^-32 or above 2^32 (the deep-tree nest's
// triangles span 2^-36 to 2^36: a float normalisation gave normals of length 1.16 and of inf there).
Vec3 unit_normal(const float* a, const float* b, const float* c) {
  const double e1[3] = {double(b[0]) - a[0], double(b[1]) - a[1], double(b[2]) - a[2]};
  const double e2[3] = {double(c[0]) - a[0], double(c[1]) - a[1], double(c[2]) - a[2]};
  const double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
  const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  return {float(n[0] / len), float(n[1] / len), float(n[2] / len)};
}

// Lexicographic (t, geom_id, prim_id): the tie rule on equal computed t.
inline bool closer(float t, std::uint32_t geom, std::uint32_t prim, const Hit& best) {
#if BUG(7)
  (void)geom;
  (void)prim;
  return t < best.t;
#else
  if (t != best.t) return t < best.t;
  return geom < best.geom_id || (geom == best.geom_id && prim < best.prim_id);
#endif
}

// Triangle: the ray's point in the triangle's frame. Candidate when tmin <= t <= bound (NaN fails).
inline bool hit_triangle(const Prim& p, const Ray& ray, float bound, float& t, float& u, float& v) {
  const float dz = p.m[2][0] * ray.dir.x + p.m[2][1] * ray.dir.y + p.m[2][2] * ray.dir.z;
  const float oz = p.m[2][0] * ray.org.x + p.m[2][1] * ray.org.y + p.m[2][2] * ray.org.z + p.m[2][3];
  t = -oz / dz;
  if (!(t >= ray.tmin && t <= bound)) return false;
  const Vec3 x{ray.org.x + t * ray.dir.x, ray.org.y + t * ray.dir.y, ray.org.z + t * ray.dir.z};
  u = p.m[0][0] * x.x + p.m[0][1] * x.y + p.m[0][2] * x.z + p.m[0][3];
  v = p.m[1][0] * x.x + p.m[1][1] * x.y + p.m[1][2] * x.z + p.m[1][3];
  return u >= 0.0f && v >= 0.0f && u + v <= 1.0f;
}

// Sphere, closest-approach form: the centre's projection onto the ray first, then the half chord from
// r^2 - |distance to the line|^2, which keeps r^2 even when |o - c| >> r. Nearer root in the interval, else
// the farther.
inline bool hit_sphere(const Prim& p, const Ray& ray, float bound, float& t) {
  const Vec3 c{p.m[0][0], p.m[0][1], p.m[0][2]};
  const float r = p.m[0][3];
  const Vec3 oc = sub(ray.org, c);
  const float dd = dot(ray.dir, ray.dir);
  const float tc = -dot(oc, ray.dir) / dd;
  const Vec3 l{oc.x + tc * ray.dir.x, oc.y + tc * ray.dir.y, oc.z + tc * ray.dir.z};
  const float h2 = r * r - dot(l, l);
  if (!(h2 >= 0.0f)) return false;
  const float h = std::sqrt(h2 / dd);
  const float t0 = tc - h, t1 = tc + h;
  if (t0 >= ray.tmin && t0 <= bound) {
    t = t0;
    return true;
  }
  if (t1 >= ray.tmin && t1 <= bound) {
    t = t1;
    return true;
  }
  return false;
}

void sphere_attributes(const Prim& p, const Ray& ray, Hit& hit) {
  const Vec3 c{p.m[0][0], p.m[0][1], p.m[0][2]};
  Vec3 n{ray.org.x + hit.t * ray.dir.x - c.x, ray.org.y + hit.t * ray.dir.y - c.y, ray.org.z + hit.t * ray.dir.z - c.z};
  const float len = std::sqrt(dot(n, n));
  n = {n.x / len, n.y / len, n.z / len};
  hit.ng = n;
  constexpr float kTwoPi = 6.28318530717958647692f, kPi = 3.14159265358979323846f;
  float u = std::atan2(n.z, n.x) / kTwoPi;
  if (u < 0.0f) u += 1.0f;
  if (u >= 1.0f) u = 0.0f;  // -tiny + 1 rounds to 1
  hit.u = u;
  hit.v = std::acos(std::min(1.0f, std::max(-1.0f, n.y))) / kPi;
}

class Bvh4 {
 public:
  int build(const twinray_geometry& g, char* error, std::size_t capacity);
  bool intersect(const Ray& ray, Hit& hit, twinray_query_stats& stats) const;
  bool occluded(const Ray& ray, twinray_query_stats& stats) const;
  void stats(twinray_build_stats& s) const;

 private:
  std::unique_ptr<BinNode> build_binary(std::vector<PrimRef>& refs, std::uint32_t start, std::uint32_t end,
                                        int depth) const;
  std::uint32_t collapse(const BinNode& n);
  // A box's area over the root's (the ABI's cost model); 1 when the root has no area (a single flat triangle
  // has some, so only an all-point scene, which loaders never give).
  double relative_area(const Box& b) const { return root_box_.area() > 0.0 ? b.area() / root_box_.area() : 1.0; }
  int slab(const Node4& node, const Ray& ray, float bound, __m128& tnear, __m128& tfar) const;
  void leaf_closest(std::uint32_t ref, const Ray& ray, Hit& hit, twinray_query_stats& stats) const;
  bool leaf_any(std::uint32_t ref, const Ray& ray, twinray_query_stats& stats) const;

  std::vector<Prim> prims_;   // in leaf order after the build
  std::vector<Node4> nodes_;  // nodes_[0] is the root unless root_ is a leaf
  std::uint32_t root_ = kEmpty;
  Box root_box_;
  std::size_t leaves_ = 0, depth_ = 0;
  double sah_ = 0.0;
};

// Binned SAH over the centroids' box; a range of coincident centroids (or a SAH that prefers no split) is cut
// at its middle. Ranges of kParallelMin and more build their first child on a thread of their own.
std::unique_ptr<BinNode> Bvh4::build_binary(std::vector<PrimRef>& refs, std::uint32_t start, std::uint32_t end,
                                            int depth) const {
  auto node = std::make_unique<BinNode>();
  Box centroids;
  for (std::uint32_t i = start; i < end; ++i) {
    node->box.grow(refs[i].box);
    centroids.grow(refs[i].centre);
  }
  const std::uint32_t n = end - start;
  if (n <= kMaxLeaf) {
    node->start = start;
    node->count = n;
    return node;
  }
  std::uint32_t mid = start + n / 2;
  int axis = -1;
  const Vec3 extent = sub(centroids.hi, centroids.lo);
  int widest = extent.x >= extent.y && extent.x >= extent.z ? 0 : (extent.y >= extent.z ? 1 : 2);
  if (depth < kSahDepth) {
    double best = std::numeric_limits<double>::infinity();
    int best_axis = -1, best_bin = 0;
    for (int a = 0; a < 3; ++a) {
      const float lo = get(centroids.lo, a), span = get(extent, a);
      if (!(span > 0.0f)) continue;
      const float scale = kBins / span;
      Box bins[kBins];
      std::uint32_t counts[kBins] = {};
      for (std::uint32_t i = start; i < end; ++i) {
        const int b = std::min(kBins - 1, static_cast<int>((get(refs[i].centre, a) - lo) * scale));
        bins[b].grow(refs[i].box);
        ++counts[b];
      }
      Box left[kBins];
      std::uint32_t nl[kBins];
      Box acc;
      std::uint32_t c = 0;
      for (int b = 0; b < kBins; ++b) {
        acc.grow(bins[b]);
        c += counts[b];
        left[b] = acc;
        nl[b] = c;
      }
      acc = Box();
      c = 0;
      for (int b = kBins - 1; b > 0; --b) {
        acc.grow(bins[b]);
        c += counts[b];
        if (nl[b - 1] == 0 || c == 0) continue;
        const double cost = left[b - 1].area() * nl[b - 1] + acc.area() * c;
        if (cost < best) {
          best = cost;
          best_axis = a;
          best_bin = b;
        }
      }
    }
    if (best_axis >= 0) {
      const float lo = get(centroids.lo, best_axis), scale = kBins / get(extent, best_axis);
      const auto it = std::partition(refs.begin() + start, refs.begin() + end, [&](const PrimRef& r) {
        return std::min(kBins - 1, static_cast<int>((get(r.centre, best_axis) - lo) * scale)) < best_bin;
      });
      mid = static_cast<std::uint32_t>(it - refs.begin());
      axis = best_axis;
    }
  }
  if (axis < 0) {  // no plane separates the centroids, or deep: object median along the widest axis
    std::nth_element(refs.begin() + start, refs.begin() + mid, refs.begin() + end,
                     [&](const PrimRef& a, const PrimRef& b) {
                       const float ka = get(a.centre, widest), kb = get(b.centre, widest);
                       return ka < kb || (ka == kb && a.index < b.index);
                     });
  }
  if (n >= kParallelMin) {
    std::thread left([&] { node->child[0] = build_binary(refs, start, mid, depth + 1); });
    node->child[1] = build_binary(refs, mid, end, depth + 1);
    left.join();
  } else {
    node->child[0] = build_binary(refs, start, mid, depth + 1);
    node->child[1] = build_binary(refs, mid, end, depth + 1);
  }
  return node;
}

// A 4-wide node over a binary interior node: open the child with the largest box until there are 4 children
// or only leaves. Returns the node's reference; the leaves' primitives are already in leaf order.
std::uint32_t Bvh4::collapse(const BinNode& n) {
  if (n.leaf()) {
    ++leaves_;
    sah_ += relative_area(n.box) * n.count;
    return leaf_ref(n.start, n.count);
  }
  const BinNode* kids[4] = {n.child[0].get(), n.child[1].get(), nullptr, nullptr};
  int count = 2;
  while (count < 4) {
    int open = -1;
    double largest = -1.0;
    for (int i = 0; i < count; ++i)
      if (!kids[i]->leaf() && kids[i]->box.area() > largest) {
        largest = kids[i]->box.area();
        open = i;
      }
    if (open < 0) break;
    const BinNode* opened = kids[open];
    kids[open] = opened->child[0].get();
#if BUG(5)
    if (count == 3) {  // "the last slot": overwrites the third child
      kids[2] = opened->child[1].get();
      break;
    }
#endif
    kids[count++] = opened->child[1].get();
  }
  const std::uint32_t index = static_cast<std::uint32_t>(nodes_.size());
  nodes_.emplace_back();
  nodes_[index].children = static_cast<std::uint32_t>(count);
  sah_ += relative_area(n.box);
  for (int i = 0; i < 4; ++i) {
    Node4& node = nodes_[index];
    if (i >= count) {
#if BUG(1)
      const float nan = std::numeric_limits<float>::quiet_NaN();
      for (int r = 0; r < 6; ++r) node.bounds[r][i] = nan;  // "no box"
#else
      for (int r = 0; r < 6; r += 2) {  // an inverted box, [+inf, -inf]: every slab test misses it
        node.bounds[r][i] = kInf;
        node.bounds[r + 1][i] = -kInf;
      }
#endif
      node.child[i] = kEmpty;
      continue;
    }
    const Box& b = kids[i]->box;
    node.bounds[0][i] = b.lo.x;
    node.bounds[1][i] = b.hi.x;
    node.bounds[2][i] = b.lo.y;
    node.bounds[3][i] = b.hi.y;
    node.bounds[4][i] = b.lo.z;
    node.bounds[5][i] = b.hi.z;
    const std::uint32_t ref = collapse(*kids[i]);  // may reallocate nodes_: `node` is taken again
    nodes_[index].child[i] = ref;
  }
  return index;
}

int Bvh4::build(const twinray_geometry& g, char* error, std::size_t capacity) {
#if BUG(10)
  _mm_setcsr(_mm_getcsr() | 0x8040);  // FTZ | DAZ: "denormals are slow"; never restored
#endif
  std::size_t total = g.sphere_count;
  for (std::size_t m = 0; m < g.mesh_count; ++m) total += g.meshes[m].triangle_count;
  if (total >= (1u << 29)) {  // a leaf reference keeps the first primitive in 29 bits
    std::snprintf(error, capacity, "bvh4: %zu primitives, at most 2^29", total);
    return TWINRAY_ERROR;
  }
  std::vector<Prim> prims;
  std::vector<PrimRef> refs;
  prims.reserve(total);
  refs.reserve(total);
  for (std::size_t m = 0; m < g.mesh_count; ++m) {
    const twinray_mesh& mesh = g.meshes[m];
    for (std::size_t k = 0; k < mesh.triangle_count; ++k) {
      const float* v[3];
      Box box;
      for (int j = 0; j < 3; ++j) {
        v[j] = mesh.positions + 3 * static_cast<std::size_t>(mesh.indices[3 * k + j]);
        box.grow(Vec3{v[j][0], v[j][1], v[j][2]});
      }
      Prim p{};
      baldwin_weber(v[0], v[1], v[2], p.m);
      p.ng = unit_normal(v[0], v[1], v[2]);
      p.geom_id = mesh.geom_id;
      p.prim_id = static_cast<std::uint32_t>(k);
      p.sphere = false;
      refs.push_back({box, box.centre(), static_cast<std::uint32_t>(prims.size())});
      prims.push_back(p);
    }
  }
  for (std::size_t s = 0; s < g.sphere_count; ++s) {
    const twinray_sphere& sp = g.spheres[s];
    Prim p{};
    p.m[0][0] = sp.center[0];
    p.m[0][1] = sp.center[1];
    p.m[0][2] = sp.center[2];
    p.m[0][3] = sp.radius;
    p.geom_id = sp.geom_id;
    p.prim_id = 0;
    p.sphere = true;
    Box box;
    box.grow(Vec3{sp.center[0] - sp.radius, sp.center[1] - sp.radius, sp.center[2] - sp.radius});
    box.grow(Vec3{sp.center[0] + sp.radius, sp.center[1] + sp.radius, sp.center[2] + sp.radius});
    refs.push_back({box, box.centre(), static_cast<std::uint32_t>(prims.size())});
    prims.push_back(p);
  }
  if (refs.empty()) return TWINRAY_OK;
  const std::unique_ptr<BinNode> top = build_binary(refs, 0, static_cast<std::uint32_t>(refs.size()), 0);
  prims_.resize(prims.size());
  for (std::size_t i = 0; i < refs.size(); ++i) prims_[i] = prims[refs[i].index];
  root_box_ = top->box;
  nodes_.reserve(refs.size() / 2 + 1);
  root_ = collapse(*top);
  // Depth of the 4-wide tree (root 1), for build_stats.
  std::vector<std::pair<std::uint32_t, std::size_t>> todo{{root_, 1}};
  while (!todo.empty()) {
    const auto [ref, d] = todo.back();
    todo.pop_back();
    depth_ = std::max(depth_, d);
    if (ref & kLeafBit) continue;
    for (std::uint32_t c : nodes_[ref].child)
      if (c != kEmpty) todo.push_back({c, d + 1});
  }
  return TWINRAY_OK;
}

// The 4 children's slabs at once: a mask of the lanes whose box overlaps [tmin, bound], their entries and exits.
int Bvh4::slab(const Node4& node, const Ray& ray, float bound, __m128& tnear, __m128& tfar) const {
  const __m128 ox = _mm_set1_ps(ray.org.x), oy = _mm_set1_ps(ray.org.y), oz = _mm_set1_ps(ray.org.z);
  const __m128 ix = _mm_set1_ps(ray.inv.x), iy = _mm_set1_ps(ray.inv.y), iz = _mm_set1_ps(ray.inv.z);
  const __m128 nx = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(node.bounds[ray.near_x]), ox), ix);
  const __m128 fx = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(node.bounds[ray.near_x ^ 1]), ox), ix);
  const __m128 ny = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(node.bounds[ray.near_y]), oy), iy);
  const __m128 fy = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(node.bounds[ray.near_y ^ 1]), oy), iy);
  const __m128 nz = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(node.bounds[ray.near_z]), oz), iz);
  const __m128 fz = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(node.bounds[ray.near_z ^ 1]), oz), iz);
  // maxps/minps return their second operand when either is NaN: the running bound goes second, so a NaN
  // plane (0 * inf) is dropped.
  tnear = _mm_max_ps(nz, _mm_max_ps(ny, _mm_max_ps(nx, _mm_set1_ps(ray.tmin))));
  tfar = _mm_min_ps(fz, _mm_min_ps(fy, _mm_min_ps(fx, _mm_set1_ps(bound))));
  return _mm_movemask_ps(_mm_cmple_ps(tnear, tfar));
}

void Bvh4::leaf_closest(std::uint32_t ref, const Ray& ray, Hit& hit, twinray_query_stats& stats) const {
  const std::uint32_t start = (ref & ~kLeafBit) >> 2, count = (ref & 3u) + 1;
  for (std::uint32_t i = start; i < start + count; ++i) {
    const Prim& p = prims_[i];
    ++stats.primitives_tested;
    float t, u = 0.0f, v = 0.0f;
    const float bound = std::min(hit.t, ray.tmax);  // equal t stays a candidate, for the tie rule
    const bool found = p.sphere ? hit_sphere(p, ray, bound, t) : hit_triangle(p, ray, bound, t, u, v);
    if (!found || !closer(t, p.geom_id, p.prim_id, hit)) continue;
    hit.t = t;
    hit.geom_id = p.geom_id;
    hit.prim_id = p.prim_id;
    if (p.sphere) {
      sphere_attributes(p, ray, hit);
    } else {
      hit.u = u;
      hit.v = v;
      hit.ng = p.ng;
    }
  }
}

bool Bvh4::leaf_any(std::uint32_t ref, const Ray& ray, twinray_query_stats& stats) const {
  const std::uint32_t start = (ref & ~kLeafBit) >> 2, count = (ref & 3u) + 1;
  for (std::uint32_t i = start; i < start + count; ++i) {
    const Prim& p = prims_[i];
    ++stats.primitives_tested;
    float t, u, v;
    if (p.sphere ? hit_sphere(p, ray, ray.tmax, t) : hit_triangle(p, ray, ray.tmax, t, u, v)) return true;
  }
  return false;
}

struct Entry {
  std::uint32_t ref;
  float tnear;
};

bool Bvh4::intersect(const Ray& ray, Hit& hit, twinray_query_stats& stats) const {
  if (root_ == kEmpty) return false;
  Entry stack[kStack];
  int top = 0;
  stack[top++] = {root_, ray.tmin};
  while (top > 0) {
    const Entry e = stack[--top];
    if (e.tnear > hit.t + hit.t * kTieSlack) continue;  // entered beyond the best hit (inf + inf: never pruned)
    if (e.ref & kLeafBit) {
      leaf_closest(e.ref, ray, hit, stats);
      continue;
    }
    const Node4& node = nodes_[e.ref];
    stats.nodes_visited += node.children;
    __m128 tn, tf;
    const float bound = std::min(ray.tmax, hit.t + hit.t * kTieSlack);
    int mask = slab(node, ray, bound, tn, tf);
    alignas(16) float near[4];
    _mm_store_ps(near, tn);
#if BUG(3)
    alignas(16) float key[4];  // "the exit orders them as well"
    _mm_store_ps(key, tf);
#else
    const float* key = near;
#endif
    // The hit lanes, sorted by key (insertion sort of at most 4), then pushed farthest first.
    Entry hits[4];
    int n = 0;
    while (mask) {
      const int i = __builtin_ctz(static_cast<unsigned>(mask));
      mask &= mask - 1;
      int j = n++;
      while (j > 0 && key[hits[j - 1].ref] > key[i]) {
        hits[j] = hits[j - 1];
        --j;
      }
      hits[j] = {static_cast<std::uint32_t>(i), near[i]};
    }
#if BUG(2)
    if (n == 4) n = 3;  // a sorting network for three: "a node rarely has four hit children"
#endif
    for (int k = n - 1; k >= 0; --k) stack[top++] = {node.child[hits[k].ref], hits[k].tnear};
  }
  return hit.geom_id != TWINRAY_INVALID_ID;
}

bool Bvh4::occluded(const Ray& ray, twinray_query_stats& stats) const {
  if (root_ == kEmpty) return false;
  std::uint32_t stack[kStack];
  int top = 0;
  stack[top++] = root_;
  while (top > 0) {
    const std::uint32_t ref = stack[--top];
    if (ref & kLeafBit) {
#if BUG(6)
      return true;  // "entering a leaf means something is there"
#endif
      if (leaf_any(ref, ray, stats)) return true;
      continue;
    }
    const Node4& node = nodes_[ref];
    stats.nodes_visited += node.children;
    __m128 tn, tf;
    int mask = slab(node, ray, ray.tmax, tn, tf);
    while (mask) {
      const int i = __builtin_ctz(static_cast<unsigned>(mask));
      mask &= mask - 1;
      stack[top++] = node.child[i];
    }
  }
  return false;
}

void Bvh4::stats(twinray_build_stats& s) const {
  s.memory_bytes = nodes_.size() * sizeof(Node4) + prims_.size() * sizeof(Prim);
  s.nodes = nodes_.size() + leaves_;
  s.leaves = leaves_;
  s.max_depth = depth_;
  s.sah_cost = sah_;
}

void* bvh4_create() { return new (std::nothrow) Bvh4(); }
void bvh4_destroy(void* self) { delete static_cast<Bvh4*>(self); }

int bvh4_build(void* self, const twinray_geometry* g, char* error, std::size_t capacity) {
  try {
    return static_cast<Bvh4*>(self)->build(*g, error, capacity);
  } catch (const std::exception& e) {
    std::snprintf(error, capacity, "bvh4: %s", e.what());
    return TWINRAY_ERROR;
  }
}

void store(const Hit& h, twinray_hit* out) {
  out->t = h.t;
  out->u = h.u;
  out->v = h.v;
  out->geom_id = h.geom_id;
  out->prim_id = h.prim_id;
  out->ng[0] = h.ng.x;
  out->ng[1] = h.ng.y;
  out->ng[2] = h.ng.z;
}

int bvh4_intersect1(const void* self, const twinray_ray* r, twinray_hit* out, twinray_query_stats* stats) {
  Hit hit;
  if (!static_cast<const Bvh4*>(self)->intersect(make_ray(*r), hit, *stats)) return 0;
  store(hit, out);
  return 1;
}

int bvh4_occluded1(const void* self, const twinray_ray* r, twinray_query_stats* stats) {
  return static_cast<const Bvh4*>(self)->occluded(make_ray(*r), *stats) ? 1 : 0;
}

void bvh4_intersect_batch(const void* self, const twinray_ray* rays, twinray_hit* hits, std::size_t count,
                          twinray_query_stats* stats) {
  const Bvh4& bvh = *static_cast<const Bvh4*>(self);
#if BUG(4)
  Hit hit;  // one hit record for the batch: "reset geom_id per ray"
  for (std::size_t i = 0; i < count; ++i) {
    hit.geom_id = hit.prim_id = TWINRAY_INVALID_ID;
    if (bvh.intersect(make_ray(rays[i]), hit, *stats)) {
      store(hit, &hits[i]);
    } else {
      hits[i] = twinray_hit{};
      hits[i].geom_id = hits[i].prim_id = TWINRAY_INVALID_ID;
    }
  }
#else
  for (std::size_t i = 0; i < count; ++i) {
    Hit hit;
    if (bvh.intersect(make_ray(rays[i]), hit, *stats)) {
      store(hit, &hits[i]);
    } else {
      hits[i] = twinray_hit{};
      hits[i].geom_id = hits[i].prim_id = TWINRAY_INVALID_ID;
    }
  }
#endif
}

void bvh4_occluded_batch(const void* self, const twinray_ray* rays, unsigned char* occluded, std::size_t count,
                         twinray_query_stats* stats) {
  const Bvh4& bvh = *static_cast<const Bvh4*>(self);
#if BUG(11)
  for (std::size_t i = 0; i < count; i += 4) {  // 4 rays, one 32-bit store
    unsigned char group[4] = {0, 0, 0, 0};
    for (std::size_t k = 0; k < 4 && i + k < count; ++k) group[k] = bvh.occluded(make_ray(rays[i + k]), *stats) ? 1 : 0;
    std::memcpy(occluded + i, group, 4);
  }
#else
  for (std::size_t i = 0; i < count; ++i) occluded[i] = bvh.occluded(make_ray(rays[i]), *stats) ? 1 : 0;
#endif
}

void bvh4_build_stats(const void* self, twinray_build_stats* s) { static_cast<const Bvh4*>(self)->stats(*s); }

const twinray_plugin_v1 kTable = {
    TWINRAY_PLUGIN_ABI_VERSION,
    "bvh4",
    TWINRAY_PLUGIN_COUNTS_TRAVERSAL | TWINRAY_PLUGIN_HONOURS_TIES,
    bvh4_create,
    bvh4_destroy,
    bvh4_build,
    bvh4_intersect1,
    bvh4_occluded1,
    bvh4_intersect_batch,
    bvh4_occluded_batch,
    bvh4_build_stats,
};

}  // namespace

TWINRAY_PLUGIN_EXPORT const twinray_plugin_v1* twinray_plugin_entry(void) { return &kTable; }
