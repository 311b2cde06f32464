// A complete, simple BVH written the way a student of a Scotty3D-style course writes one (bounding boxes,
// nodes with start, size and two children, a bucketed SAH build, an explicit-stack traversal), as a twinray
// plugin. Built as is, it is correct and earns full marks on correctness in `twinray grade`
// (tests/test_grade_plugins.cpp). Built with -DSCOTTY_BUG=<n>, it carries one of the classic bugs of
// issue 10, each where a student would make it:
//
//   1 FIRST_HIT        closest hit = the first hit found
//   2 EARLY_EXIT       the far child is skipped whenever the near child's subtree found a hit
//   3 SLAB_NO_SWAP     slab test without swapping t0/t1 for negative direction components
//   4 LOST_PRIMITIVE   every partition drops the primitive at the split position
//   5 BEFORE_TMIN      hits before tmin accepted (the tests check t >= 0 instead)
//   6 ZERO_DIRECTION   segfault on rays with an exactly zero direction component
//   7 INFINITE_LOOP    loops forever on rays with a hit exactly at tmin
//   8 SHARED_STACK     the traversal stack lives in the BVH object: a data race between threads
//   9 ANYHIT_TMAX      any-hit ignores tmax
//  10 OPENS_FILES      not a bug but a cheat: while answering, it reads a file and writes another (the
//                      grader's sandbox must stop it; a file it manages to write proves it escaped)
//  11 SWAPPED_UV       the right triangle at the right t, with u and v swapped (the hit point is elsewhere)
//  12 FLIPPED_NORMAL   ng = cross(p2 - p0, p1 - p0): the back of every surface
//  13 INFINITE_T       t = +inf on rays without an end, whatever the hit (a "no hit yet" value left in place)
//  14 TINY_SAH         a correct tree whose reported SAH cost is 1e-6 (no tree of a non-empty scene costs
//                      less than 1, its root)
//  15 CONCURRENT_CRASH  crashes when two closest-hit calls are inside it at once (what a race on a shared
//                      buffer does): only concurrent calls show it, and no single ray replays it
//  16 MESH_INDEX_ID    a triangle's geom_id is its mesh's index in the geometry's array, not the mesh's geom_id:
//                      right wherever meshes are numbered 0, 1, 2, ... with no sphere in between
//
// The third red-team round's bugs (what students and engineers write that the rounds above did not cover):
//
//  17 NEG_ZERO_SIGN     slab test with the near/far planes picked by `dir < 0`: a -0 component counts as
//                       positive while its inverse is -inf, so the box is missed from inside its slab
//  18 NAN_SLAB          no case for a zero direction component: an origin exactly on a box's plane gives
//                       0 * inf = NaN, std::max(NaN, t0) keeps the NaN and `!(t0 <= t1)` rejects the box
//  19 INDEX_16BIT       the primitive index kept in 16 bits: triangle 65536 + i is tested and reported as i
//  20 STACK_32          a traversal stack of 32 entries that drops what does not fit: right on shallow trees
//  21 ANYHIT_LEAF_BOX   any-hit answers "occluded" as soon as the ray enters a leaf's box
//  22 MT_EPSILON        Moller-Trumbore with |det| < 1e-6 taken as parallel: small triangles and grazing rays
//                       are missed (claims no watertightness: the test is not watertight)
//  23 BACKFACE_UV       u and v swapped on hits from the back (the triangle "flipped to face the ray")
//  24 LAST_RAY_CACHE    a ray from the same origin as the thread's previous ray starts with that ray's hit
//                       distance (x 1.01) as its bound ("coherent rays hit at similar distances"): answers
//                       depend on the rays traced before
//  25 LEAK_PER_QUERY    every closest-hit query allocates a 64 KiB traversal stack with new[] and never frees it
//  26 OVERFIT_SMALL     exact on scenes of up to 10,000 primitives (the size of the public quick suite's),
//                       the first hit found on larger ones ("a fast mode for big scenes")
//  27 RANDOM_SPLIT      the split axis chosen at random from the clock: a different, still correct tree on
//                       every run
//  28 SORTED_PRIM_ID    prim_id is the primitive's place in the builder's reordered array, not its index in
//                       the mesh
//  29 LEAF_SKIPS_LAST   leaves are scanned up to size - 1: the last primitive of every leaf is never tested
//  30 SPHERE_UNIT_DIR   the sphere test assumes a unit direction (a = 1): t is right only when |dir| = 1
//  31 EPSILON_TMIN      tmin ignored; hits need t > 1e-4 instead (the self-intersection epsilon)
//  32 ANYHIT_NO_SPHERES any-hit tests triangles only
//  33 INDEX_20BIT       the primitive index packed into 20 bits of the leaf: triangle 2^20 + i is i
//
// The fourth red-team round's:
//
//  34 BACKFACE_CULL     triangles seen from the back are missed (Moller-Trumbore's culling branch, copied
//                       for a renderer of closed, outward-facing meshes)
//  35 LEAF_COUNT_3BIT   the leaf's primitive count kept in 3 bits ("leaves hold at most 4"), but the builder
//                       keeps up to 16 primitives in a leaf that no split improves: 8 to 15 lose their last
//                       eight, 16 test none
//  36 NODE_INDEX_16BIT  child node indices stored in 16 bits ("64k nodes is plenty"): node 65536 + i is i
//  37 ANYHIT_STACK_32   any-hit reuses the closest-hit traversal (nearer child first) with bug 20's stack of
//                       32 entries that drops what does not fit, and stops at the first hit
//
// The fifth red-team round's:
//
//  38 SLAB_Z_NO_SWAP    the slab test unrolled by hand, and the z slab's near/far swap forgotten: boxes are
//                       missed by rays going down in z only
//  39 BOX_STRICT_FLAT   `if (tnear >= tfar) return false` ("an empty interval") and no padding: a flat box
//                       (the leaf of a wall or floor in a coordinate plane) has tnear == tfar and is never hit
//  40 FLOAT_SLAB        the slab test in float (ported from a GPU kernel), exit not padded: rounding can put
//                       the exit an ulp before the entry where a ray crosses a box near an edge or corner
//  41 STALE_BOUND       when the right child is the nearer one, its subtree is searched with the ray's
//                       original tmax and every hit found there replaces the closest ("tmax shrinks as hits
//                       are found", but that branch passes the unshrunk ray)
//  42 LAST_LEAF_SHORT   the leaf at the end of the primitive array scans one primitive less (its end taken
//                       as inclusive, n - 1)
//  43 BIN_BOUNDARY_DROP the partition copies `c < split` left and `c > split` right: a primitive whose
//                       centroid lies exactly on the split plane is in no child
//  44 CENTROID_BOX      a node's box is the box of its primitives' centroids, not of the primitives
//  45 UV_ROTATED        barycentrics relative to the wrong vertex: u is p2's weight, v is p0's
//  46 STATIC_INV_CACHE  the inverse direction cached in statics for the next ray with the same direction
//                       ("coherent rays share directions"): threads overwrite each other's
//  47 SPHERE_NAIVE      the sphere test in float with b^2 - 4ac (the textbook's quadratic): far and small
//                       spheres lose their hits to cancellation
//  48 SPHERE_NEAR_ROOT  only the near root of the sphere test: rays from inside a sphere miss it
//  49 ANYHIT_TMIN_ZERO  any-hit tests primitives from t = 0 instead of tmin (the shadow ray's own surface
//                       occludes it)
//  50 LEAF_FIRST_HIT    a leaf returns its first hit primitive to the traversal rather than its closest
//  51 QUADRATIC_BUILD   a full-sweep SAH that rebuilds both sides' boxes from scratch for every candidate
//                       plane: O(n^2) per node, right but endless on large meshes
//  52 STACK_64          bug 20 with 64 entries
//  53 ANYHIT_FIXED_ORDER_32  any-hit pushes the left child, then the right (popped first), on a stack of 32
//                       entries that drops what does not fit
//  54 LAZY_BUILD        build() keeps the primitives and the first query builds the tree, unlocked: queries
//                       that start together build it together (build_stats, called right after build,
//                       reports the tree not built yet)
//
// The sixth red-team round's:
//
//  55 OPEN_INTERVAL     hits exactly at the ray's tmin or tmax rejected ("(tmin, tmax)", as some books write it)
//  56 SEGMENT_FIRST_HIT a closest-hit query with a finite tmax returns the first hit found ("a segment is a
//                       shadow ray")
//  57 FLOAT_SLAB_ABS_EPS the slab test in float, the exit padded by an absolute 1e-5 ("epsilon for robustness")
//                       (not caught: docs/grading.md, "Bugs the grader does not catch", says why)
//  58 GEOM_ID_8BIT      (geom_id, prim_id) packed into one 32-bit word, 8 bits of geometry: geometry 256 + i is i
//  59 SLIVER_DROP       the builder drops "degenerate" triangles (area below 1e-6 of the longest edge squared)
//                       and numbers the ones it keeps 0, 1, 2, ...: every later prim_id of the mesh is shifted
//                       (caught by closest-slivers, procedural:sliver-soup)
//  60 KD_SPLIT_PRUNE    kd-tree habits in a BVH: children ordered by the direction's sign on the split axis, and
//                       the far child taken to start at the split plane, so a hit before the plane skips it
//  61 UV_LAST_CANDIDATE every candidate is tested against the whole ray and writes u, v through the test's out
//                       arguments: the reported u, v are the last candidate's, not the closest one's
//  62 NORMALISED_T      the direction normalised on entry, t reported (and tmin, tmax read) as a distance
//  63 BUILD_NO_FALLBACK when no SAH split helps, split at the middle of the centroids' box and recurse even when
//                       one side is empty: coincident centroids recurse until the stack overflows
//  64 SPHERE_TMIN_EPS   the sphere test keeps the roots beyond 0.001 (a well-known book's shadow-acne fix)
//                       instead of tmin
//  65 SPHERE_U_SHIFTED  the sphere's u = atan2(z, x) / 2 pi + 0.5: in [0, 1], half a turn off the convention
//  66 MT_DOUBLE_WT      Moller-Trumbore in double, no epsilon, and still claims watertightness
//  67 STACK_RING_32     a traversal stack of 32 entries used as a ring: when full, a push overwrites the oldest
//
// The eighth red-team round's:
//
//  68 VERTEX_INDEX_16BIT vertex indices read as 16 bits ("the assignment's OBJs have under 65k vertices"):
//                       a triangle that uses vertex 65536 + i is built and tested with vertex i
//  69 TIE_PRIM_FIRST    equal t resolves to the lower prim_id first, then the lower geom_id (the key packed
//                       as prim << 32 | geom): wrong only where a later geometry's copy has the lower prim_id
//  70 GLOBAL_TREE       the tree lives in process-global vectors ("there is only one scene"): a second
//                       instance in the same process overwrites the first's (caught by the two-instances check,
//                       whose worker holds two instances; docs/grading.md, "Two instances in one process")
//  71 BUCKET_MAX_DROP   the builder sorts primitives into bucket lists; the largest centroid lands in bucket
//                       nb (index = nb * (c - lo) / extent, unclamped; the vector has nb + 1 lists "to be
//                       safe"), and the copy back stops at nb - 1: that primitive is lost at every split
//  72 BUCKET_NAN_EXTENT no guard for a flat centroid axis: 0 / 0 = NaN, cast to int, indexes the buckets far
//                       out of range (a flat node: a wall, a grid, identical triangles)
//  73 LEAF_ARRAY_8      a leaf holds at most 8 primitive indices (a fixed array in the node); a leaf the
//                       builder cannot split keeps its first 8 and drops the rest
//  74 BOX_UNIT_DIR      the slab test works in distances along the normalised direction, compared with tmin,
//                       tmax and the closest t, which are in units of |dir|
//  75 CHILD_SWAP_FLAGS  children ordered nearer first by swapping indices and entry times, but not the two
//                       "box hit" flags (a missed box's entry stays tmin)
//  76 SPHERE_STALE_PRIM one hit record per thread reused by every test; the sphere test fills in t and geom_id
//                       but not prim_id ("a sphere has no triangles"): a sphere hit keeps the prim_id of the
//                       thread's last triangle hit
//  77 MESH_VERTEX_OFFSET the meshes merged into one vertex array, each mesh's indices offset by the triangles
//                       of the meshes before it instead of their vertices
//  78 PRUNE_BREAK       "the stack is sorted by distance": the first popped node that starts beyond the closest
//                       hit ends the traversal (break instead of continue)
//  79 INDEX_IN_FLOAT    the leaf's first primitive index kept in a float (a GPU-style float4 node): exact up to
//                       2^24 (not caught: docs/grading.md, "Bugs the grader does not catch", says why)
//  80 SPHERE_ROOT_BY_ZERO the sphere's root picked by its sign (the near one unless it is behind the origin),
//                       then checked against [tmin, tmax]: a ray whose tmin lies between the roots misses
//  81 SHARED_MAILBOX    mailboxing in the instance: every primitive remembers the id of the last ray that tested
//                       it, and ray ids count per thread from 1, so another thread's ray of the same number skips
//                       the primitive
//
// The tenth red-team round's (docs/grading.md, "The tenth round"):
//
//  82 MORTON_MAP_DEDUP  the primitives put in Morton order (30-bit codes of their centroids in the scene's box)
//                       through a std::map keyed by the code: primitives whose centroids share a code are dropped
//  83 QUANTISED_NEAREST child boxes stored quantised to 8 bits of their parent's box (a compressed wide-BVH
//                       node) and rounded to nearest, not outward: a child's box can shrink by half a step
//  84 LEAF_CLIP_EXIT    a leaf's primitives are tested against the ray clipped to the leaf's box ([tmin, exit]):
//                       a hit on the box's exit face whose float-rounded t lands past the exit is lost
//  85 CENTRE_ORDER_PRUNE children ordered by where the ray passes their box centres, and that distance is what
//                       the pruning compares with the closest hit: a box that starts before the hit but whose
//                       centre lies beyond it is skipped
//  86 PRIM_ID_GLOBAL    a triangle's prim_id counts the triangles of the meshes before it (its place in the
//                       scene's triangle list): right only for geometry with one mesh
//  87 UV_LEAF_WINDING   the triangles of a leaf stored with one winding (p1 and p2 swapped for those facing away
//                       from the leaf's first, for a culling SIMD kernel): their u and v come out swapped
//  88 SHADOW_CACHE_NO_TMAX any-hit first tests the thread's last occluder ("shadow rays from one point hit the
//                       same blocker"), against [tmin, inf): it occluded once, so it is taken to occlude again
//  89 THREAD_STACK_MAP  one traversal stack per thread, kept in a static std::unordered_map keyed by the thread's
//                       id and filled on first use without a lock: threads that arrive together insert together
//  90 ANYHIT_SOLID_SPHERE any-hit treats a sphere as a solid ball: occluded when the segment overlaps the ball,
//                       also when it starts and ends inside it without crossing the surface
//  91 PRUNE_NO_SLACK    nodes pruned when their entry is beyond the closest hit's float-rounded t, no slack:
//                       an identical triangle (a tie) in a box entered exactly at t is skipped when t rounded down
//  92 FMA_EDGES         the watertight test's edge functions with fused multiply-adds (what -march=native
//                       -ffp-contract=fast makes of them): a shared edge's two functions are no longer exact
//                       negations, and it still claims watertightness
//  93 PARALLEL_STRICT   a ray parallel to a slab must be strictly inside it (`o <= lo || o >= hi` rejects): a
//                       ray in the plane of a box face (a wall's own plane, a flat box) misses it
//  94 SAH_VOLUME        the SAH weighs the children by their boxes' volume, not their surface area ("the
//                       probability of hitting a box"): a valid but poorer tree; a flat box has volume 0, so
//                       on a planar mesh no split ever beats the leaf and ranges split by count in list order
//  95 PIVOT_FIRST       no SAH: the range is partitioned around its first primitive's centroid on the longest
//                       axis (one quicksort step, "about the median"): on input sorted along that axis the
//                       pivot is the smallest, every split peels off its equals, and the tree degenerates
//                       towards a list (traversal stacks sized to the tree, so only speed suffers)
//  96 NO_BEST_T_PRUNE   the closest-hit traversal clips its box tests to [tmin, tmax] only, never to the
//                       closest hit so far, and pops every pending node: right answers, more nodes visited
//  97 SPHERE_ANYHIT_T0  any-hit tests spheres from t = 0 ("a shadow ray starts at its surface"), triangles
//                       from tmin: a sphere root between 0 and tmin occludes
//
// Triangles use the watertight test of Woop, Benthin and Wald (JCGT 2013) in double precision, so the plugin
// can claim TWINRAY_PLUGIN_WATERTIGHT; equal t resolves to the lower (geom_id, prim_id), so it claims
// TWINRAY_PLUGIN_HONOURS_TIES; it counts its traversal. It reports its SAH cost in the unit model of
// docs/plugin-abi.md.

#include "twinray_plugin.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <cstdint>
#include <cstring>
#include <limits>
#include <map>
#include <thread>
#include <unordered_map>
#include <new>
#include <utility>
#include <vector>

#ifndef SCOTTY_BUG
#define SCOTTY_BUG 0
#endif
#define BUG(n) (SCOTTY_BUG == (n))

namespace {

struct Vec3 {
  double x = 0.0, y = 0.0, z = 0.0;
  double operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
  double& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
};
Vec3 operator-(const Vec3& a, const Vec3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
Vec3 operator+(const Vec3& a, const Vec3& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
Vec3 operator*(double s, const Vec3& a) { return {s * a.x, s * a.y, s * a.z}; }
double dot(const Vec3& a, const Vec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
Vec3 cross(const Vec3& a, const Vec3& b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
Vec3 load(const float* f) { return {f[0], f[1], f[2]}; }

struct Ray {
  Vec3 point, dir, inv_dir;
  double tmin = 0.0, tmax = 0.0;
};

#if BUG(46)
// The last direction seen and its inverse, which the box test reads (one copy for every thread).
Vec3 g_last_dir{NAN, NAN, NAN}, g_inv_dir;
#endif

struct BBox {
  Vec3 min{INFINITY, INFINITY, INFINITY};
  Vec3 max{-INFINITY, -INFINITY, -INFINITY};

  void enclose(const Vec3& p) {
    for (int a = 0; a < 3; ++a) {
      min[a] = std::min(min[a], p[a]);
      max[a] = std::max(max[a], p[a]);
    }
  }
  void enclose(const BBox& b) {
    if (b.empty()) return;  // its +-infinite corners would swallow this box
    enclose(b.min);
    enclose(b.max);
  }
  bool empty() const { return min.x > max.x; }
  Vec3 center() const { return 0.5 * (min + max); }
#if BUG(94)
  double volume() const {
    if (empty()) return 0.0;
    const Vec3 e = max - min;
    return e.x * e.y * e.z;
  }
#endif
  double surface_area() const {
    if (empty()) return 0.0;
    const Vec3 e = max - min;
    return 2.0 * (e.x * e.y + e.y * e.z + e.z * e.x);
  }

#if BUG(6)
  // Slabs dispatched on the sign of the direction; a zero component "cannot happen", so it has no entry.
  using Slab = void (*)(double lo, double hi, double o, double inv, double& t0, double& t1);
  static void slab_positive(double lo, double hi, double o, double inv, double& t0, double& t1) {
    t0 = std::max(t0, (lo - o) * inv);
    t1 = std::min(t1, (hi - o) * inv);
  }
  static void slab_negative(double lo, double hi, double o, double inv, double& t0, double& t1) {
    t0 = std::max(t0, (hi - o) * inv);
    t1 = std::min(t1, (lo - o) * inv);
  }
#endif

  // Where the ray enters and leaves the box within [times[0], times[1]]; false when it misses.
  bool hit(const Ray& ray, double times[2]) const {
    double t0 = times[0], t1 = times[1];
    for (int a = 0; a < 3; ++a) {
#if BUG(6)
      static const Slab slabs[3] = {slab_negative, nullptr, slab_positive};
      slabs[(ray.dir[a] > 0.0) - (ray.dir[a] < 0.0) + 1](min[a], max[a], ray.point[a], ray.inv_dir[a], t0, t1);
#elif BUG(17)
      const bool negative = ray.dir[a] < 0.0;  // false for -0, whose inverse is -inf
      const double near = ((negative ? max[a] : min[a]) - ray.point[a]) * ray.inv_dir[a];
      const double far = ((negative ? min[a] : max[a]) - ray.point[a]) * ray.inv_dir[a];
      t0 = std::max(t0, near);
      t1 = std::min(t1, far);
#elif BUG(18)
      double near = (min[a] - ray.point[a]) * ray.inv_dir[a];
      double far = (max[a] - ray.point[a]) * ray.inv_dir[a];
      if (near > far) std::swap(near, far);
      t0 = std::max(near, t0);
      t1 = std::min(far, t1);
#elif BUG(40) || BUG(57)
      if (ray.dir[a] == 0.0) {
        if (ray.point[a] < min[a] || ray.point[a] > max[a]) return false;
        continue;
      }
      // In float, as the GPU kernel it was ported from: each difference and product rounds to float.
      const float o = static_cast<float>(ray.point[a]), inv = static_cast<float>(ray.inv_dir[a]);
      float near = (static_cast<float>(min[a]) - o) * inv, far = (static_cast<float>(max[a]) - o) * inv;
      if (near > far) std::swap(near, far);
      t0 = std::max(t0, static_cast<double>(near));
      t1 = std::min(t1, static_cast<double>(far));
#else
      // A ray parallel to the slab is inside it or not at all. Left to the division, an origin exactly on a
      // face gives 0 * inf = NaN, and the slab would cut the ray away.
      if (ray.dir[a] == 0.0) {
#if BUG(93)
        if (ray.point[a] <= min[a] || ray.point[a] >= max[a]) return false;  // "strictly inside the slab"
#else
        if (ray.point[a] < min[a] || ray.point[a] > max[a]) return false;
#endif
        continue;
      }
#if BUG(46)
      const double inv = g_inv_dir[a];
#elif BUG(74)
      // The inverse of the normalised direction: near and far are distances, not multiples of |dir|.
      const double inv = ray.inv_dir[a] * std::sqrt(dot(ray.dir, ray.dir));
#else
      const double inv = ray.inv_dir[a];
#endif
      double near = (min[a] - ray.point[a]) * inv;
      double far = (max[a] - ray.point[a]) * inv;
#if BUG(38)
      if (a != 2 && near > far) std::swap(near, far);  // x and y written first; z pasted from an older draft
#elif !BUG(3)
      if (near > far) std::swap(near, far);
#endif
      t0 = std::max(t0, near);
      t1 = std::min(t1, far);
#endif
    }
    // Pad the exit by a few double ulps: a flat box (a grid in a plane) has entry == exit, and rounding must
    // not turn that into a miss.
#if BUG(39)
    if (t0 >= t1) return false;  // "an empty interval"
#elif BUG(40)
    if (t0 > t1) return false;
#elif BUG(57)
    if (t0 > t1 + 1e-5) return false;  // "an epsilon for robustness"
#elif BUG(18)
    t1 *= 1.0 + 1e-12;
    if (!(t0 <= t1)) return false;  // "NaN-safe"
#else
    t1 *= 1.0 + 1e-12;
    if (t0 > t1) return false;
#endif
    times[0] = t0;
    times[1] = t1;
    return true;
  }
};

struct Trace {
  bool hit = false;
  double t = INFINITY;  // rounded to float precision
  float u = 0.0f, v = 0.0f;
  twinray_id geom = TWINRAY_INVALID_ID, prim = TWINRAY_INVALID_ID;
  const void* primitive = nullptr;  // what was hit, for the attributes computed once at the end
};

#if BUG(76)
// The prim_id of this thread's hit record, which every triangle test that hits writes and the sphere test
// leaves as it is.
thread_local twinray_id g_record_prim = 0;
#endif

// The smallest t a hit may have and the largest, as the primitive tests see them.
double lowest_t(const Ray& ray) {
#if BUG(5)
  (void)ray;
  return 0.0;
#elif BUG(31)
  (void)ray;
  return 1e-4;
#else
  return ray.tmin;
#endif
}

// Whether a hit at t counts: t in [lowest_t, tmax], where tmax is the ray's end or the closest hit so far.
bool counts(const Ray& ray, double t, double tmax) {
#if BUG(55)
  if (t == ray.tmin || t == ray.tmax) return false;  // "(tmin, tmax)": the ray's own ends are excluded
#endif
  return t >= lowest_t(ray) && t <= tmax;
}

double length(const Vec3& a) { return std::sqrt(dot(a, a)); }

struct Primitive {
  const twinray_mesh* mesh = nullptr;      // a triangle of this mesh...
  const twinray_sphere* sphere = nullptr;  // ...or this sphere
  twinray_id index = 0;                    // the triangle's index in its mesh
  twinray_id mesh_index = 0;               // its mesh's place in the geometry's mesh array
  twinray_id slot = 0;                     // its place in the builder's (reordered) array, for bug 28
  twinray_id kept = 0;                     // its place among the triangles the builder kept, for bug 59
#if BUG(87)
  bool rewound = false;  // stored with p1 and p2 swapped, to face the way its leaf's first triangle faces
#endif

#if BUG(68)
  // "Our meshes have fewer than 65,536 vertices": indices kept as 16 bits.
  Vec3 vertex(int k) const { return load(mesh->positions + 3 * static_cast<std::size_t>(static_cast<std::uint16_t>(mesh->indices[3 * index + k]))); }
#else
  Vec3 vertex(int k) const { return load(mesh->positions + 3 * static_cast<std::size_t>(mesh->indices[3 * index + k])); }
#endif

  BBox bbox() const {
    BBox b;
    if (mesh) {
      for (int k = 0; k < 3; ++k) b.enclose(vertex(k));
    } else {
      const Vec3 c = load(sphere->center);
      const double r = sphere->radius;
      b.enclose(c - Vec3{r, r, r});
      b.enclose(c + Vec3{r, r, r});
    }
    return b;
  }

  // A hit in [lowest_t, tmax], t rounded to float before the test (the interval holds for the t reported).
  Trace hit(const Ray& ray, double tmax) const { return mesh ? hit_triangle(ray, tmax) : hit_sphere(ray, tmax); }

  // The unit geometric normal (triangles: counter-clockwise front; spheres: outward) and, for spheres, the
  // (u, v) of twinray_plugin.h, at the hit.
  void attributes(const Ray& ray, const Trace& t, twinray_hit& out) const {
    Vec3 n;
    if (mesh) {
      n = cross(vertex(1) - vertex(0), vertex(2) - vertex(0));
    } else {
      n = ray.point + t.t * ray.dir - load(sphere->center);
      const double len = length(n);
      const Vec3 unit = (1.0 / len) * n;
      const double two_pi = 6.283185307179586;
      double phi = std::atan2(unit.z, unit.x);
#if BUG(65)
      phi += two_pi / 2.0;  // "atan2 is in [-pi, pi]: shift it to [0, 2 pi]"
#else
      if (phi < 0.0) phi += two_pi;
#endif
      out.u = std::min(static_cast<float>(phi / two_pi), 0.99999994f);
      out.v = static_cast<float>(std::acos(std::clamp(unit.y, -1.0, 1.0)) / (two_pi / 2.0));
    }
    const double len = length(n);
    for (int k = 0; k < 3; ++k) out.ng[k] = static_cast<float>(n[k] / len);
  }

  // Woop, Benthin, Wald: shear the triangle into the ray's space, then three edge functions whose signs
  // decide the hit. Computed from the same vertex values in the same order, the function of an edge shared
  // by two triangles is the exact negation of the other's, so no ray slips between them.
#if BUG(22) || BUG(66)
  // Moller-Trumbore, as in the textbooks, with a fixed epsilon on the determinant (bug 66: in double, none).
  Trace hit_triangle(const Ray& ray, double tmax) const {
    Trace tr;
    const Vec3 e1 = vertex(1) - vertex(0), e2 = vertex(2) - vertex(0);
    const Vec3 p = cross(ray.dir, e2);
    const double det = dot(e1, p);
    if (BUG(22) ? std::fabs(det) < 1e-6 : det == 0.0) return tr;  // "parallel"
    const double inv = 1.0 / det;
    const Vec3 s0 = ray.point - vertex(0);
    const double u = dot(s0, p) * inv;
    if (u < 0.0 || u > 1.0) return tr;
    const Vec3 q = cross(s0, e1);
    const double v = dot(ray.dir, q) * inv;
    if (v < 0.0 || u + v > 1.0) return tr;
    const double t = static_cast<float>(dot(e2, q) * inv);
    if (!counts(ray, t, tmax)) return tr;
    tr.hit = true;
    tr.t = t;
    tr.u = static_cast<float>(u);
    tr.v = static_cast<float>(v);
    tr.geom = mesh->geom_id;
    tr.prim = index;
    tr.primitive = this;
    return tr;
  }
#else
  Trace hit_triangle(const Ray& ray, double tmax) const {
    const Vec3& d = ray.dir;
    int kz = std::fabs(d.x) > std::fabs(d.y) ? (std::fabs(d.x) > std::fabs(d.z) ? 0 : 2) : (std::fabs(d.y) > std::fabs(d.z) ? 1 : 2);
    int kx = (kz + 1) % 3, ky = (kx + 1) % 3;
    if (d[kz] < 0.0) std::swap(kx, ky);
    const double sx = d[kx] / d[kz], sy = d[ky] / d[kz], sz = 1.0 / d[kz];
    const Vec3 a = vertex(0) - ray.point, b = vertex(1) - ray.point, c = vertex(2) - ray.point;
    const double ax = a[kx] - sx * a[kz], ay = a[ky] - sy * a[kz];
    const double bx = b[kx] - sx * b[kz], by = b[ky] - sy * b[kz];
    const double cx = c[kx] - sx * c[kz], cy = c[ky] - sy * c[kz];
#if BUG(92)
    // What -march=native -ffp-contract=fast makes of the three differences of products.
    const double u = std::fma(cx, by, -(cy * bx)), v = std::fma(ax, cy, -(ay * cx)), w = std::fma(bx, ay, -(by * ax));
#else
    const double u = cx * by - cy * bx, v = ax * cy - ay * cx, w = bx * ay - by * ax;
#endif
    Trace tr;
    if ((u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0)) return tr;
    const double det = u + v + w;
    if (det == 0.0) return tr;
#if BUG(34)
    if (det < 0.0) return tr;  // the back of the triangle: "culled"
#endif
    const double t = static_cast<float>((u * sz * a[kz] + v * sz * b[kz] + w * sz * c[kz]) / det);
    if (!counts(ray, t, tmax)) return tr;
    tr.hit = true;
    tr.t = t;
#if BUG(45)
    tr.u = static_cast<float>(w / det);  // the weights of p2 and p0
    tr.v = static_cast<float>(u / det);
#else
    tr.u = static_cast<float>(v / det);
    tr.v = static_cast<float>(w / det);
#endif
#if BUG(23)
    if (det < 0.0) std::swap(tr.u, tr.v);  // the back of the triangle: "flip it to face the ray"
#endif
#if BUG(87)
    if (rewound) std::swap(tr.u, tr.v);  // stored as (p0, p2, p1): the weights of the stored p1 and p2
#endif
    tr.geom = BUG(16) ? mesh_index : mesh->geom_id;
#if BUG(58)
    tr.geom &= 0xFFu;  // the top 8 bits of a packed (geom << 24 | prim) word
#endif
    tr.prim = BUG(28) ? slot : (BUG(59) || BUG(86) ? kept : index);
#if BUG(76)
    g_record_prim = tr.prim;
#endif
    tr.primitive = this;
    return tr;
  }
#endif

  // The sphere's answer for a root t in the ray's interval.
  Trace sphere_hit(double t) const {
    Trace tr;
    tr.hit = true;
    tr.t = t;
    tr.geom = BUG(58) ? sphere->geom_id & 0xFFu : sphere->geom_id;
#if BUG(76)
    tr.prim = g_record_prim;  // the record's prim_id, from the thread's last triangle hit
#else
    tr.prim = 0;
#endif
    tr.primitive = this;
    return tr;
  }

  // Both roots of |o + t d - c| = r with the discriminant taken from the closest-approach vector (no
  // cancellation for far spheres) and the near root through Vieta (no cancellation for huge ones).
#if BUG(47)
  // The textbook quadratic, in float.
  Trace hit_sphere(const Ray& ray, double tmax) const {
    Trace tr;
    float f[3], d[3];
    for (int k = 0; k < 3; ++k) {
      f[k] = static_cast<float>(ray.point[k]) - sphere->center[k];
      d[k] = static_cast<float>(ray.dir[k]);
    }
    const float r = sphere->radius;
    const float a = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    const float b = 2.0f * (f[0] * d[0] + f[1] * d[1] + f[2] * d[2]);
    const float c = f[0] * f[0] + f[1] * f[1] + f[2] * f[2] - r * r;
    const float disc = b * b - 4.0f * a * c;
    if (disc < 0.0f) return tr;
    const float root = std::sqrt(disc);
    for (const float t : {(-b - root) / (2.0f * a), (-b + root) / (2.0f * a)})
      if (t >= lowest_t(ray) && t <= tmax) return sphere_hit(t);
    return tr;
  }
#else
  Trace hit_sphere(const Ray& ray, double tmax) const {
    const Vec3 f = ray.point - load(sphere->center);
#if BUG(30)
    const double r = sphere->radius, a = 1.0, b = dot(f, ray.dir);  // "directions are normalised"
#else
    const double r = sphere->radius, a = dot(ray.dir, ray.dir), b = dot(f, ray.dir);
#endif
    const Vec3 l = f - (b / a) * ray.dir;
    const double disc = a * (r * r - dot(l, l));
    Trace tr;
    if (!(disc >= 0.0)) return tr;
    const double flen = std::sqrt(dot(f, f));
    const double q = -(b + std::copysign(std::sqrt(disc), b));
    const double r0 = q == 0.0 ? 0.0 : (flen - r) * (flen + r) / q, r1 = q == 0.0 ? 0.0 : q / a;
#if BUG(80)
    // "The near root, unless it is behind the origin", and then the interval.
    const double near = static_cast<float>(std::min(r0, r1)), far = static_cast<float>(std::max(r0, r1));
    const double t = near >= 0.0 ? near : far;
    if (counts(ray, t, tmax)) return sphere_hit(t);
    return tr;
#endif
#if BUG(48)
    for (const double root : {std::min(r0, r1)}) {  // "the near root is the hit"
#else
    for (const double root : {std::min(r0, r1), std::max(r0, r1)}) {
#endif
      const double t = static_cast<float>(root);
#if BUG(64)
      if (t > 0.001 && t <= tmax) return sphere_hit(t);  // "ignore hits very near zero"
#else
      if (counts(ray, t, tmax)) return sphere_hit(t);
#endif
    }
    return tr;
  }
#endif
};

#if BUG(90)
// "A ball blocks the light": whether the ray's interval overlaps the ball (both roots, not the surface).
bool ball_overlaps(const Primitive& p, const Ray& ray, double tmax) {
  const Vec3 f = ray.point - load(p.sphere->center);
  const double r = p.sphere->radius, a = dot(ray.dir, ray.dir), b = dot(f, ray.dir);
  const Vec3 l = f - (b / a) * ray.dir;
  const double disc = a * (r * r - dot(l, l));
  if (!(disc >= 0.0)) return false;
  const double centre = -b / a, half = std::sqrt(disc) / a;
  return centre - half <= tmax && centre + half >= lowest_t(ray);
}
#endif

// The tie rule of twinray (hit.h): smaller t first, then the lower (geom_id, prim_id).
bool precedes(const Trace& a, const Trace& b) {
  if (!b.hit) return a.hit;
  if (a.t != b.t) return a.t < b.t;
#if BUG(69)
  if (a.prim != b.prim) return a.prim < b.prim;  // the key (prim << 32 | geom), compared as one number
  return a.geom < b.geom;
#else
  if (a.geom != b.geom) return a.geom < b.geom;
  return a.prim < b.prim;
#endif
}

struct Node {
  BBox bbox;
  std::size_t start = 0, size = 0, l = 0, r = 0;
  int axis = -1;       // the split plane, for bug 60 (-1: split by count)
  double split = 0.0;
  bool is_leaf() const { return l == r; }
};

struct StackEntry {
  std::size_t node;
  double entry;         // where the ray enters the node's box
  std::size_t hits_at;  // hits found when it was pushed (for bug 2)
  bool stale = false;   // searched with the ray's original tmax (for bug 41)
};

// The primitives of a leaf, as the traversal reads them.
std::size_t leaf_count(const Node& node) {
#if BUG(35)
  return node.size & 7u;  // three bits of a packed field
#elif BUG(73)
  return std::min<std::size_t>(node.size, 8);  // the node's array of primitive indices holds 8
#else
  return node.size;
#endif
}

#if BUG(82)
// The low 10 bits of x spread to every third bit.
std::uint32_t spread_bits(std::uint32_t x) {
  x &= 0x3FFu;
  x = (x | x << 16) & 0x030000FFu;
  x = (x | x << 8) & 0x0300F00Fu;
  x = (x | x << 4) & 0x030C30C3u;
  x = (x | x << 2) & 0x09249249u;
  return x;
}

// The primitives in Morton order of their centroids (10 bits per axis over the centroids' box), "sorted by a
// map" keyed by the code: emplace keeps the first primitive of each code and drops the others.
std::vector<Primitive> morton_order(const std::vector<Primitive>& prims) {
  BBox box;
  for (const Primitive& p : prims) box.enclose(p.bbox().center());
  std::map<std::uint32_t, Primitive> sorted;
  for (const Primitive& p : prims) {
    const Vec3 c = p.bbox().center();
    std::uint32_t code = 0;
    for (int a = 0; a < 3; ++a) {
      const double extent = box.max[a] - box.min[a];
      const double f = extent > 0.0 ? (c[a] - box.min[a]) / extent : 0.0;
      code |= spread_bits(std::min<std::uint32_t>(1023u, static_cast<std::uint32_t>(f * 1024.0))) << (2 - a);
    }
    sorted.emplace(code, p);
  }
  std::vector<Primitive> out;
  out.reserve(sorted.size());
  for (const auto& entry : sorted) out.push_back(entry.second);
  return out;
}
#endif

#if BUG(70)
// "There is only one scene": the tree lives in the process, not in the instance.
std::vector<Primitive>& global_primitives() {
  static std::vector<Primitive> v;
  return v;
}
std::vector<Node>& global_nodes() {
  static std::vector<Node> v;
  return v;
}
#endif

// The meshes merged into one vertex array and one index array (bug 77), and a mesh record for each that
// points into them.
struct MergedMeshes {
  std::vector<float> positions;
  std::vector<twinray_id> indices;
  std::vector<twinray_mesh> meshes;
};

constexpr std::size_t kMaxDepth = 96;
constexpr std::size_t kBuckets = 12;
constexpr std::size_t kMaxLeafSize = 4;

class BVH {
 public:
  MergedMeshes merged;  // bug 77's copy of the meshes

  void build(std::vector<Primitive>&& prims) {
    primitives_ = std::move(prims);
#if BUG(82)
    primitives_ = morton_order(primitives_);  // locality for the build and the traversal
#endif
#if BUG(54)
    built_ = false;  // built on first use: "a scene that is never traced costs nothing"
  }

  // The tree, built by the first query that needs it (no lock: "it happens once").
  void ensure_built() const {
    if (built_) return;
    lazy_arrivals_.fetch_add(1);  // the test's widening of the race window (lazy_build_pause)
    const_cast<BVH*>(this)->build_tree();
    built_ = true;
  }

  void build_tree() {
#endif
    nodes_.clear();
    depth_ = 0;
    if (primitives_.empty()) return;
    nodes_.reserve(2 * primitives_.size());
    build_node(0, primitives_.size(), 0);
    for (std::size_t k = 0; k < primitives_.size(); ++k) primitives_[k].slot = static_cast<twinray_id>(k);
#if BUG(83)
    quantise_child_boxes();
#endif
#if BUG(87)
    rewind_leaves();
#endif
#if BUG(81)
    mailbox_.assign(primitives_.size(), 0);
#endif
  }

  // Closest hit; counts nodes whose box was tested and primitives tested.
  Trace hit(const Ray& ray, twinray_query_stats& stats) const {
#if BUG(54)
    ensure_built();
#endif
    Trace closest;
    if (nodes_.empty()) return closest;
#if BUG(24)
    // The previous ray of this thread, if it came from the same point, says how far to look.
    thread_local Vec3 last_origin{NAN, NAN, NAN};
    thread_local double last_t = INFINITY;
    const bool coherent = ray.point.x == last_origin.x && ray.point.y == last_origin.y && ray.point.z == last_origin.z;
    const double bound = coherent ? std::min(ray.tmax, last_t * 1.01) : ray.tmax;
    struct Remember {
      const Ray& ray;
      const Trace& closest;
      ~Remember() {
        last_origin = ray.point;
        last_t = closest.hit ? closest.t : INFINITY;
      }
    } remember{ray, closest};
#else
    const double bound = ray.tmax;
#endif
#if BUG(25)
    StackEntry* leaked = new StackEntry[65536 / sizeof(StackEntry)];  // "freed by the OS at exit"
    std::memset(static_cast<void*>(leaked), 0, 65536 / sizeof(StackEntry) * sizeof(StackEntry));
#endif
#if BUG(26)
    const bool fast_mode = primitives_.size() > 10000;
#endif
    double root_times[2] = {lowest_t(ray), bound};
    ++stats.nodes_visited;
    if (!nodes_[0].bbox.hit(ray, root_times)) return closest;
#if BUG(8)
    std::vector<StackEntry>& stack = stack_;  // one stack for every thread
    if (stack.size() < kMaxDepth + 1) stack.resize(kMaxDepth + 1);
#elif BUG(89)
    // One stack per thread, made on the thread's first query ("the map only grows once per thread").
    static std::unordered_map<std::thread::id, std::vector<StackEntry>> stacks;
    std::vector<StackEntry>& stack = stacks[std::this_thread::get_id()];
    if (stack.size() < kMaxDepth + 1) stack.resize(kMaxDepth + 1);
#elif BUG(20)
    std::array<StackEntry, 32> stack;  // "32 levels is more than any tree needs"
#elif BUG(52)
    std::array<StackEntry, 64> stack;  // "64 levels is more than any tree needs"
#elif BUG(67)
    std::array<StackEntry, 32> stack;  // a ring: "when it is full, the oldest entry is the least useful"
#elif BUG(95)
    thread_local std::vector<StackEntry> stack;  // as deep as the tree
    if (stack.size() < depth_ + 2) stack.resize(depth_ + 2);
#else
    std::array<StackEntry, kMaxDepth + 1> stack;
#endif
#if BUG(61)
    float last_u = 0.0f, last_v = 0.0f;  // the primitive test's out arguments
#endif
#if BUG(81)
    thread_local std::uint32_t rays_of_this_thread = 0;
    const std::uint32_t ray_id = ++rays_of_this_thread;  // "unique enough"
#endif
    std::size_t sp = 0, hits = 0;
    stack[sp++] = {0, root_times[0], 0};
    while (sp > 0) {
#if BUG(67)
      const StackEntry e = stack[--sp % stack.size()];
#else
      const StackEntry e = stack[--sp];
#endif
      // A node that starts beyond the best hit cannot improve it; the slack keeps an equal-t hit in another
      // subtree (a tie) reachable although its box entry is computed in double and t is rounded to float.
#if BUG(78)
      if (closest.hit && e.entry > closest.t * (1.0 + 1e-6)) break;  // "everything below it is farther"
#elif BUG(91)
      if (closest.hit && e.entry > closest.t) continue;  // "beyond the closest hit"
#elif BUG(96)
      // every pending node is opened: "the leaf test already rejects hits beyond the closest"
#else
      if (closest.hit && e.entry > closest.t * (1.0 + 1e-6)) continue;
#endif
#if BUG(2)
      if (hits > e.hits_at) continue;  // "the near child already found something"
#endif
      const Node& node = nodes_[e.node];
      if (node.is_leaf()) {
#if BUG(84)
        // The ray clipped to the leaf's box: nothing in the leaf lies beyond where the ray leaves it.
        double leaf_times[2] = {lowest_t(ray), closest.hit ? closest.t : bound};
        const double leaf_exit = node.bbox.hit(ray, leaf_times) ? leaf_times[1] : -INFINITY;
#endif
        std::size_t i = node.start;
        while (i < leaf_end(node)) {
#if BUG(81)
          if (mailbox_[i] == ray_id) {  // "this ray has tested it already"
            ++i;
            continue;
          }
          mailbox_[i] = ray_id;
#endif
          ++stats.primitives_tested;
#if BUG(41)
          const Trace t = primitives_[i].hit(ray, e.stale || !closest.hit ? bound : closest.t);
#elif BUG(61)
          const Trace t = primitives_[i].hit(ray, bound);  // every candidate against the whole ray
          if (t.hit) {
            last_u = t.u;
            last_v = t.v;
          }
#elif BUG(84)
          const Trace t = primitives_[i].hit(ray, std::min(closest.hit ? closest.t : bound, leaf_exit));
#else
          const Trace t = primitives_[i].hit(ray, closest.hit ? closest.t : bound);
#endif
          if (!t.hit) {
            ++i;
            continue;
          }
#if BUG(7)
          if (t.t == ray.tmin) continue;  // meant to skip self-hits, and forgot to advance i
#endif
#if BUG(41)
          if (e.stale || precedes(t, closest)) {  // the bound decided it: "every hit within tmax is closer"
#else
          if (precedes(t, closest)) {
#endif
            closest = t;
            ++hits;
#if BUG(1)
            return closest;
#endif
#if BUG(26)
            if (fast_mode) return closest;
#endif
#if BUG(56)
            if (std::isfinite(ray.tmax)) return closest;  // "a segment only asks whether something is in the way"
#endif
          }
#if BUG(50)
          break;  // the leaf's hit
#endif
          ++i;
        }
        continue;
      }
#if BUG(41)
      const double limit = closest.hit && !e.stale ? closest.t * (1.0 + 1e-6) : bound;
#elif BUG(91)
      const double limit = closest.hit ? closest.t : bound;
#elif BUG(96)
      const double limit = bound;  // the ray's own tmax
#else
      const double limit = closest.hit ? closest.t * (1.0 + 1e-6) : bound;
#endif
      double tl[2] = {lowest_t(ray), limit}, tr[2] = {lowest_t(ray), limit};
      stats.nodes_visited += 2;
      const bool hl = nodes_[node.l].bbox.hit(ray, tl), hr = nodes_[node.r].bbox.hit(ray, tr);
      // Far child first, so that the near one is popped first.
#if BUG(20) || BUG(52)
      const auto push = [&](const StackEntry& e) {
        if (sp < stack.size()) stack[sp++] = e;  // full: dropped
      };
#elif BUG(67)
      const auto push = [&](const StackEntry& e) { stack[sp++ % stack.size()] = e; };  // full: the oldest goes
#else
      const auto push = [&](const StackEntry& e) { stack[sp++] = e; };
#endif
#if BUG(75)
      // Nearer child first: order the two by where the ray enters them (the hit flags stay where they were).
      std::size_t first = node.l, second = node.r;
      double first_t = tl[0], second_t = tr[0];
      if (second_t < first_t) {
        std::swap(first, second);
        std::swap(first_t, second_t);
      }
      if (hl && hr) {
        push({second, second_t, hits, e.stale});
        push({first, first_t, hits, e.stale});
      } else if (hl) {
        push({first, first_t, hits, e.stale});
      } else if (hr) {
        push({second, second_t, hits, e.stale});
      }
      continue;
#endif
#if BUG(85)
      // Nearer child first, by where the ray passes its box's centre, and that is the entry the pruning reads.
      const auto centre_t = [&](std::size_t n) {
        return dot(nodes_[n].bbox.center() - ray.point, ray.dir) / dot(ray.dir, ray.dir);
      };
      const double cl = centre_t(node.l), cr = centre_t(node.r);
      if (hl && hr) {
        const bool left_first = cl <= cr;
        push(left_first ? StackEntry{node.r, cr, hits} : StackEntry{node.l, cl, hits});
        push(left_first ? StackEntry{node.l, cl, hits} : StackEntry{node.r, cr, hits});
      } else if (hl) {
        push({node.l, cl, hits});
      } else if (hr) {
        push({node.r, cr, hits});
      }
      continue;
#endif
      if (hl && hr) {
#if BUG(60)
        // As in a kd-tree: the near child is the one on the ray's side of the split plane, and the far child
        // starts where the ray crosses the plane.
        const bool kd = node.axis >= 0 && ray.dir[node.axis] != 0.0;
        const bool left_near = kd ? ray.dir[node.axis] > 0.0 : tl[0] <= tr[0];
        if (kd) {
          const double plane = (node.split - ray.point[node.axis]) * ray.inv_dir[node.axis];
          double& far_entry = left_near ? tr[0] : tl[0];
          far_entry = std::max(far_entry, plane);
        }
#else
        const bool left_near = tl[0] <= tr[0];
#endif
        // Bug 41: the right child, when it is the nearer, is searched with the unshrunk ray.
        const bool right_stale = e.stale || (BUG(41) && !left_near);
        push(left_near ? StackEntry{node.r, tr[0], hits, e.stale} : StackEntry{node.l, tl[0], hits, e.stale});
        push(left_near ? StackEntry{node.l, tl[0], hits, e.stale} : StackEntry{node.r, tr[0], hits, right_stale});
      } else if (hl) {
        push({node.l, tl[0], hits, e.stale});
      } else if (hr) {
        push({node.r, tr[0], hits, e.stale});
      }
    }
#if BUG(61)
    if (closest.hit) {
      closest.u = last_u;
      closest.v = last_v;
    }
#endif
    return closest;
  }

  bool any_hit(const Ray& ray, twinray_query_stats& stats) const {
#if BUG(54)
    ensure_built();
#endif
    if (nodes_.empty()) return false;
#if BUG(9)
    const double tmax = INFINITY;
#else
    const double tmax = ray.tmax;
#endif
#if BUG(37)
    return any_hit_nearer_first(ray, tmax, stats);
#endif
#if BUG(88)
    // The thread's last occluder first: "it blocked the last shadow ray, it blocks this one".
    thread_local std::size_t last_occluder = static_cast<std::size_t>(-1);
    if (last_occluder < primitives_.size() && primitives_[last_occluder].hit(ray, INFINITY).hit) return true;
#endif
#if BUG(95)
    thread_local std::vector<std::size_t> stack;  // as deep as the tree
    if (stack.size() < depth_ + 2) stack.resize(depth_ + 2);
#else
    std::array<std::size_t, kMaxDepth + 1> stack;
#endif
    std::size_t sp = 0;
    stack[sp++] = 0;
    ++stats.nodes_visited;
    double root_times[2] = {lowest_t(ray), tmax};
    if (!nodes_[0].bbox.hit(ray, root_times)) return false;
    while (sp > 0) {
      const Node& node = nodes_[stack[--sp]];
      if (node.is_leaf()) {
#if BUG(21)
        return true;  // children are only pushed when their box is hit: "the leaf's box is hit, so it's occluded"
#endif
        for (std::size_t i = node.start; i < leaf_end(node); ++i) {
#if BUG(32)
          if (primitives_[i].sphere != nullptr) continue;  // shadows come from meshes
#endif
          ++stats.primitives_tested;
#if BUG(90)
          if (primitives_[i].sphere != nullptr) {
            if (ball_overlaps(primitives_[i], ray, tmax)) return true;
            continue;
          }
#endif
#if BUG(97)
          if (primitives_[i].sphere != nullptr) {
            Ray from_zero = ray;  // "a shadow ray starts at its surface"
            from_zero.tmin = 0.0;
            if (primitives_[i].hit(from_zero, tmax).hit) return true;
            continue;
          }
#endif
#if BUG(88)
          if (primitives_[i].hit(ray, tmax).hit) {
            last_occluder = i;
            return true;
          }
#else
          if (primitives_[i].hit(ray, tmax).hit) return true;
#endif
        }
        continue;
      }
      for (const std::size_t child : {node.l, node.r}) {
        double times[2] = {lowest_t(ray), tmax};
        ++stats.nodes_visited;
#if BUG(53)
        if (nodes_[child].bbox.hit(ray, times) && sp < 32) stack[sp++] = child;  // "32 levels is plenty"; full: dropped
#else
        if (nodes_[child].bbox.hit(ray, times)) stack[sp++] = child;
#endif
      }
    }
    return false;
  }

#if BUG(37)
  // The closest-hit traversal, nearer child first, ending at the first hit: "any-hit is closest-hit that
  // stops early", with the same fixed stack.
  bool any_hit_nearer_first(const Ray& ray, double tmax, twinray_query_stats& stats) const {
    std::array<std::size_t, 32> stack;  // "32 levels is more than any tree needs"
    std::size_t sp = 0;
    ++stats.nodes_visited;
    double root_times[2] = {lowest_t(ray), tmax};
    if (!nodes_[0].bbox.hit(ray, root_times)) return false;
    stack[sp++] = 0;
    while (sp > 0) {
      const Node& node = nodes_[stack[--sp]];
      if (node.is_leaf()) {
        for (std::size_t i = node.start; i < node.start + node.size; ++i) {
          ++stats.primitives_tested;
          if (primitives_[i].hit(ray, tmax).hit) return true;
        }
        continue;
      }
      double tl[2] = {lowest_t(ray), tmax}, tr[2] = {lowest_t(ray), tmax};
      stats.nodes_visited += 2;
      const bool hl = nodes_[node.l].bbox.hit(ray, tl), hr = nodes_[node.r].bbox.hit(ray, tr);
      const auto push = [&](std::size_t n) {
        if (sp < stack.size()) stack[sp++] = n;  // full: dropped
      };
      const bool left_near = tl[0] <= tr[0];
      if (hl && hr) {
        push(left_near ? node.r : node.l);
        push(left_near ? node.l : node.r);
      } else if (hl) {
        push(node.l);
      } else if (hr) {
        push(node.r);
      }
    }
    return false;
  }
#endif

#if BUG(83)
  // Each child's box stored in 8 bits per coordinate over its parent's box (a compressed node), each
  // coordinate rounded to the nearest step: a min can move up and a max down.
  void quantise_child_boxes() {
    std::vector<BBox> exact;
    exact.reserve(nodes_.size());
    for (const Node& n : nodes_) exact.push_back(n.bbox);
    for (std::size_t n = 0; n < nodes_.size(); ++n) {
      if (nodes_[n].is_leaf()) continue;
      const BBox& parent = exact[n];
      for (const std::size_t c : {nodes_[n].l, nodes_[n].r})
        for (int a = 0; a < 3; ++a) {
          const double step = (parent.max[a] - parent.min[a]) / 255.0;
          if (!(step > 0.0)) continue;
          nodes_[c].bbox.min[a] = parent.min[a] + std::round((exact[c].min[a] - parent.min[a]) / step) * step;
          nodes_[c].bbox.max[a] = parent.min[a] + std::round((exact[c].max[a] - parent.min[a]) / step) * step;
        }
    }
  }
#endif

#if BUG(87)
  // One winding per leaf, the first triangle's: the others that face away are stored with p1 and p2 swapped.
  void rewind_leaves() {
    for (const Node& n : nodes_) {
      if (!n.is_leaf()) continue;
      const Primitive* first = nullptr;
      for (std::size_t i = n.start; i < n.start + n.size; ++i) {
        Primitive& p = primitives_[i];
        if (!p.mesh) continue;
        if (!first) {
          first = &p;
          continue;
        }
        const Vec3 n0 = cross(first->vertex(1) - first->vertex(0), first->vertex(2) - first->vertex(0));
        const Vec3 n1 = cross(p.vertex(1) - p.vertex(0), p.vertex(2) - p.vertex(0));
        p.rewound = dot(n0, n1) < 0.0;
      }
    }
  }
#endif

  // The unit-cost SAH of docs/plugin-abi.md: area-weighted interior nodes plus area-weighted leaf sizes.
  void stats(twinray_build_stats& s) const {
    s.nodes = nodes_.size();
    s.max_depth = depth_;
    s.memory_bytes = nodes_.capacity() * sizeof(Node) + primitives_.capacity() * sizeof(Primitive);
    if (nodes_.empty()) return;
    const double root = nodes_[0].bbox.surface_area();
    for (const Node& n : nodes_) {
      const double weight = root > 0.0 ? n.bbox.surface_area() / root : 1.0;
      s.leaves += n.is_leaf() ? 1 : 0;
      s.sah_cost += weight * (n.is_leaf() ? static_cast<double>(n.size) : 1.0);
    }
  }

 private:
  // One past the last primitive of a leaf, as the traversals read it.
  std::size_t leaf_end(const Node& node) const {
    std::size_t end = node.start + leaf_count(node);
#if BUG(29)
    --end;
#elif BUG(42)
    if (end == primitives_.size()) --end;  // "the last index is n - 1"
#endif
    return end;
  }

  std::size_t new_node(const BBox& box, std::size_t start, std::size_t size) {
    Node n;
    n.bbox = box;
#if BUG(79)
    n.start = static_cast<std::size_t>(static_cast<float>(start));  // the .w of a float4
#else
    n.start = start;
#endif
    n.size = size;
    nodes_.push_back(n);
#if BUG(54)
    lazy_build_pause();
#endif
    return nodes_.size() - 1;
  }

#if BUG(54)
  // Test-only widening of the race window (not part of the bug as a student writes it). Two builders that
  // run one after the other build the same tree into the same slots (a deterministic build; std::partition of
  // a range already partitioned moves nothing), so the unlocked lazy build does harm only when a second
  // builder's nodes_.clear() lands while the first is part-way through its nodes and their pushes then
  // interleave: on a loaded machine, or a scene whose build takes a millisecond, that was left to the
  // scheduler, and GradePlugins.LazyBuildRacesInTheFirstConcurrentRound was flaky. Here every builder of the
  // lazy build sleeps 200 us after each of its first 32 nodes (so two builders' pushes alternate, on one core
  // or two), and the first builder, after its 8th node, waits (up to 2 s) until a second query has found the
  // tree unbuilt too, whose clear() then reuses the first builder's slots. A query alone (the single-threaded
  // round, `twinray trace`) waits 2 s once and builds a correct tree; the first concurrent round of the
  // thread-safety check always tears it.
  void lazy_build_pause() const {
    if (built_) return;
    thread_local std::size_t pushed = 0;
    thread_local const void* instance = nullptr;
    if (instance != this) {  // this thread's first node of this instance's lazy build
      instance = this;
      pushed = 0;
    }
    ++pushed;
    if (pushed == 8 && lazy_arrivals_.load() < 2) {
      const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(2);
      while (lazy_arrivals_.load() < 2 && std::chrono::steady_clock::now() < until)
        std::this_thread::sleep_for(std::chrono::microseconds(100));
    }
    if (pushed <= 32) std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
#endif

  // Bucketed SAH over primitive centroids (the textbook's 12 buckets). Falls back to a split by count in the
  // middle when the centroids do not spread (identical boxes) or the tree gets deep, so it always ends.
  std::size_t build_node(std::size_t start, std::size_t end, std::size_t depth) {
    depth_ = std::max(depth_, depth);
    BBox box, centroids;
    for (std::size_t i = start; i < end; ++i) {
      const BBox b = primitives_[i].bbox();
      box.enclose(b);
      centroids.enclose(b.center());
    }
#if BUG(44)
    const std::size_t index = new_node(centroids, start, end - start);  // "the node's bounds"
#else
    const std::size_t index = new_node(box, start, end - start);
#endif
    const std::size_t size = end - start;
    if (size <= kMaxLeafSize) return index;

#if BUG(94)
    double best_cost = static_cast<double>(size) * box.volume();  // "the chance that a ray hits a box is its volume"
#else
    double best_cost = static_cast<double>(size) * box.surface_area();  // cost of a leaf
#endif
    int best_axis = -1;
    double best_split = 0.0;
    // The SAH cost of a split into two non-empty sides; the cheapest so far is kept.
    const auto consider = [&](int axis, double plane, const BBox& left, std::size_t nl, const BBox& right,
                              std::size_t nr) {
      if (nl == 0 || nr == 0) return;
#if BUG(94)
      const double cost = box.volume() + static_cast<double>(nl) * left.volume() + static_cast<double>(nr) * right.volume();
#else
      const double cost = box.surface_area() + static_cast<double>(nl) * left.surface_area() +
                          static_cast<double>(nr) * right.surface_area();
#endif
      if (cost < best_cost) {
        best_cost = cost;
        best_axis = axis;
        best_split = plane;
      }
    };
#if BUG(27)
    // One axis, at random: "random splits are good enough"
    static std::uint64_t state = static_cast<std::uint64_t>(std::chrono::steady_clock::now().time_since_epoch().count()) | 1;
    state ^= state << 13;
    state ^= state >> 7;
    state ^= state << 17;
    const int random_axis = static_cast<int>(state % 3);
#endif
#if BUG(95)
    {
      // One quicksort step around the range's first primitive, on the centroids' longest axis.
      const Vec3 ext = centroids.max - centroids.min;
      const int axis = ext.x >= ext.y && ext.x >= ext.z ? 0 : (ext.y >= ext.z ? 1 : 2);
      const double pivot = primitives_[start].bbox().center()[axis];
      std::size_t mid = start + size / 2;  // every centroid equal to the pivot: a split by count
      const auto it = std::partition(primitives_.begin() + static_cast<std::ptrdiff_t>(start),
                                     primitives_.begin() + static_cast<std::ptrdiff_t>(end),
                                     [&](const Primitive& p) { return p.bbox().center()[axis] <= pivot; });
      const std::size_t split_at = static_cast<std::size_t>(it - primitives_.begin());
      if (split_at != start && split_at != end) mid = split_at;
      const std::size_t l = build_node(start, mid, depth + 1);
      const std::size_t r = build_node(mid, end, depth + 1);
      nodes_[index].l = l;
      nodes_[index].r = r;
      return index;
    }
#endif
    if (depth < kMaxDepth / 2) {
      for (int axis = 0; axis < 3; ++axis) {
#if BUG(27)
        if (axis != random_axis) continue;
#endif
        const double lo = centroids.min[axis], extent = centroids.max[axis] - lo;
#if !BUG(72)
        if (!(extent > 0.0)) continue;
#endif
#if BUG(51)
        // Every primitive's centroid is a candidate plane, and each candidate's two boxes are built afresh.
        for (std::size_t candidate = start; candidate < end; ++candidate) {
          const double plane = primitives_[candidate].bbox().center()[axis];
          BBox left, right;
          std::size_t nl = 0, nr = 0;
          for (std::size_t i = start; i < end; ++i) {
            const BBox b = primitives_[i].bbox();
            const bool goes_left = b.center()[axis] < plane;
            (goes_left ? left : right).enclose(b);
            (goes_left ? nl : nr) += 1;
          }
          consider(axis, plane, left, nl, right, nr);
        }
        continue;
#endif
        std::array<BBox, kBuckets> buckets;
        std::array<std::size_t, kBuckets> counts{};
        const auto bucket_of = [&](const Primitive& p) {
          const double c = p.bbox().center()[axis];
#if BUG(72)
          int b = static_cast<int>(static_cast<double>(kBuckets) * (c - lo) / extent);
          if (b == static_cast<int>(kBuckets)) b = static_cast<int>(kBuckets) - 1;  // the largest centroid
          return static_cast<std::size_t>(b);
#else
          return std::min(kBuckets - 1, static_cast<std::size_t>(static_cast<double>(kBuckets) * (c - lo) / extent));
#endif
        };
        for (std::size_t i = start; i < end; ++i) {
          const std::size_t k = bucket_of(primitives_[i]);
          buckets[k].enclose(primitives_[i].bbox());
          ++counts[k];
        }
        for (std::size_t split = 1; split < kBuckets; ++split) {
          BBox left, right;
          std::size_t nl = 0, nr = 0;
          for (std::size_t k = 0; k < kBuckets; ++k) {
            (k < split ? left : right).enclose(buckets[k]);
            (k < split ? nl : nr) += counts[k];
          }
          consider(axis, lo + extent * static_cast<double>(split) / static_cast<double>(kBuckets), left, nl, right, nr);
        }
      }
    }

    std::size_t mid = start + size / 2;  // a split by count, when no plane splits
    std::size_t right_end = end;
    if (best_axis >= 0) {
#if BUG(43)
      // Two lists, filled in one pass and copied back: the primitives exactly on the plane go to neither.
      std::vector<Primitive> left, right, on_plane;
      for (std::size_t i = start; i < end; ++i) {
        const double c = primitives_[i].bbox().center()[best_axis];
        (c < best_split ? left : (c > best_split ? right : on_plane)).push_back(primitives_[i]);
      }
      if (!left.empty() && !right.empty()) {
        std::size_t k = start;
        for (const std::vector<Primitive>* list : {&left, &right, &on_plane})
          for (const Primitive& p : *list) primitives_[k++] = p;
        mid = start + left.size();
        right_end = mid + right.size();
      }
#elif BUG(71)
      // The primitives sorted into bucket lists and copied back bucket by bucket. A centroid at the top of the
      // range lands in list kBuckets (there is one more list "to be safe"), which the copy back never reaches;
      // the slots it leaves keep what they held before.
      const double lo = centroids.min[best_axis], extent = centroids.max[best_axis] - lo;
      const auto split_bucket = static_cast<std::size_t>(std::llround((best_split - lo) / extent * static_cast<double>(kBuckets)));
      std::vector<std::vector<Primitive>> lists(kBuckets + 1);
      for (std::size_t i = start; i < end; ++i) {
        const double c = primitives_[i].bbox().center()[best_axis];
        lists[static_cast<std::size_t>(static_cast<double>(kBuckets) * (c - lo) / extent)].push_back(primitives_[i]);
      }
      std::size_t k = start, left_end = start;
      for (std::size_t b = 0; b < kBuckets; ++b) {
        for (const Primitive& p : lists[b]) primitives_[k++] = p;
        if (b + 1 == split_bucket) left_end = k;
      }
      if (left_end > start && left_end < end) mid = left_end;
#else
      const auto it = std::partition(primitives_.begin() + static_cast<std::ptrdiff_t>(start),
                                     primitives_.begin() + static_cast<std::ptrdiff_t>(end), [&](const Primitive& p) {
                                       return p.bbox().center()[best_axis] < best_split;
                                     });
      const std::size_t split_at = static_cast<std::size_t>(it - primitives_.begin());
      if (split_at != start && split_at != end) {
        mid = split_at;
        nodes_[index].axis = best_axis;
        nodes_[index].split = best_split;
      }
#endif
    } else if (size <= 4 * kMaxLeafSize && depth < kMaxDepth / 2) {
      return index;  // no split beats a leaf, and it is small enough to be one
    }
#if BUG(63)
    else {
      // "No good plane: split the centroids' box in the middle of its longest axis."
      const Vec3 extent = centroids.max - centroids.min;
      const int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : (extent.y >= extent.z ? 1 : 2);
      const double plane = centroids.center()[axis];
      const auto it = std::partition(primitives_.begin() + static_cast<std::ptrdiff_t>(start),
                                     primitives_.begin() + static_cast<std::ptrdiff_t>(end),
                                     [&](const Primitive& p) { return p.bbox().center()[axis] < plane; });
      mid = static_cast<std::size_t>(it - primitives_.begin());  // all on one side: the same range again
    }
#endif

#if BUG(4)
    const std::size_t l = build_node(start, mid, depth + 1);
    const std::size_t r = build_node(std::min(mid + 1, right_end - 1), right_end, depth + 1);  // primitive `mid` is lost
#else
    const std::size_t l = build_node(start, mid, depth + 1);
    const std::size_t r = build_node(mid, right_end, depth + 1);
#endif
#if BUG(36)
    nodes_[index].l = static_cast<std::uint16_t>(l);
    nodes_[index].r = static_cast<std::uint16_t>(r);
#else
    nodes_[index].l = l;
    nodes_[index].r = r;
#endif
    return index;
  }

#if BUG(70)
  std::vector<Primitive>& primitives_ = global_primitives();
  std::vector<Node>& nodes_ = global_nodes();
#else
  std::vector<Primitive> primitives_;
  std::vector<Node> nodes_;
#endif
  std::size_t depth_ = 0;
#if BUG(8)
  mutable std::vector<StackEntry> stack_;
#endif
#if BUG(54)
  mutable bool built_ = false;
  mutable std::atomic<int> lazy_arrivals_{0};  // queries that found the tree unbuilt (lazy_build_pause)
#endif
#if BUG(81)
  mutable std::vector<std::uint32_t> mailbox_;  // the last ray id that tested each primitive
#endif
};

Ray to_ray(const twinray_ray* r) {
  Ray ray;
  ray.point = load(r->org);
  ray.dir = load(r->dir);
  ray.inv_dir = {1.0 / ray.dir.x, 1.0 / ray.dir.y, 1.0 / ray.dir.z};
#if BUG(46)
  // Three divisions saved for every ray that repeats the last direction (a camera's rows, a light's shadows).
  if (!(ray.dir.x == g_last_dir.x && ray.dir.y == g_last_dir.y && ray.dir.z == g_last_dir.z)) {
    g_last_dir = ray.dir;
    g_inv_dir = ray.inv_dir;
  }
#endif
  ray.tmin = r->tmin;
  ray.tmax = r->tmax;
#if BUG(62)
  // "Directions are normalised, so t is the distance along the ray": tmin, tmax and the reported t too.
  ray.dir = (1.0 / length(ray.dir)) * ray.dir;
  ray.inv_dir = {1.0 / ray.dir.x, 1.0 / ray.dir.y, 1.0 / ray.dir.z};
#endif
  return ray;
}

#if BUG(59)
// A triangle whose area is below 1e-6 of its longest edge squared: a sliver.
bool is_sliver(const twinray_mesh& mesh, std::size_t i) {
  Vec3 p[3];
  for (std::size_t k = 0; k < 3; ++k)
    p[k] = load(mesh.positions + 3 * static_cast<std::size_t>(mesh.indices[3 * i + k]));
  const double area = 0.5 * length(cross(p[1] - p[0], p[2] - p[0]));
  double longest = 0.0;
  for (int k = 0; k < 3; ++k) longest = std::max(longest, dot(p[(k + 1) % 3] - p[k], p[(k + 1) % 3] - p[k]));
  return area < 1e-6 * longest;
}
#endif

void* scotty_create() { return new (std::nothrow) BVH(); }

void scotty_destroy(void* self) { delete static_cast<BVH*>(self); }

#if BUG(77)
// One vertex array and one index array for the whole scene ("fewer pointers to chase"); mesh m's indices are
// offset by the triangles of the meshes before it, where it should be their vertices.
const twinray_mesh* merge_meshes(const twinray_geometry* g, MergedMeshes& merged) {
  std::size_t offset = 0;
  for (std::size_t m = 0; m < g->mesh_count; ++m) {
    const twinray_mesh& mesh = g->meshes[m];
    merged.positions.insert(merged.positions.end(), mesh.positions, mesh.positions + 3 * mesh.vertex_count);
    for (std::size_t i = 0; i < 3 * mesh.triangle_count; ++i)
      merged.indices.push_back(static_cast<twinray_id>(mesh.indices[i] + offset));
    offset += mesh.triangle_count;
  }
  merged.positions.insert(merged.positions.end(), {0.0f, 0.0f, 0.0f});  // room past the last vertex
  std::size_t first = 0;
  for (std::size_t m = 0; m < g->mesh_count; ++m) {
    twinray_mesh copy = g->meshes[m];
    copy.positions = merged.positions.data();
    copy.vertex_count = merged.positions.size() / 3;
    copy.indices = merged.indices.data() + 3 * first;
    merged.meshes.push_back(copy);
    first += copy.triangle_count;
  }
  return merged.meshes.data();
}
#endif

int scotty_build(void* self, const twinray_geometry* g, char* error, std::size_t capacity) {
  try {
    std::vector<Primitive> prims;
#if BUG(77)
    twinray_geometry merged_geometry = *g;
    merged_geometry.meshes = merge_meshes(g, static_cast<BVH*>(self)->merged);
    g = &merged_geometry;
#endif
#if BUG(59)
    twinray_id kept = 0;
#endif
    for (std::size_t m = 0; m < g->mesh_count; ++m)
#if BUG(59)
      for (std::size_t i = (kept = 0, 0); i < g->meshes[m].triangle_count; ++i)
#else
      for (std::size_t i = 0; i < g->meshes[m].triangle_count; ++i)
#endif
#if BUG(19)
        prims.push_back({&g->meshes[m], nullptr, static_cast<std::uint16_t>(i), static_cast<twinray_id>(m)});
#elif BUG(33)
        prims.push_back({&g->meshes[m], nullptr, static_cast<twinray_id>(i & 0xFFFFFu), static_cast<twinray_id>(m)});
#elif BUG(86)
      {
        Primitive p{&g->meshes[m], nullptr, static_cast<twinray_id>(i), static_cast<twinray_id>(m)};
        std::size_t before = 0;  // the triangles of the meshes before this one
        for (std::size_t k = 0; k < m; ++k) before += g->meshes[k].triangle_count;
        p.kept = static_cast<twinray_id>(before + i);  // "the scene's triangle index"
        prims.push_back(p);
      }
#elif BUG(59)
      {
        if (is_sliver(g->meshes[m], i)) continue;  // "degenerate: it can only cause trouble"
        Primitive p{&g->meshes[m], nullptr, static_cast<twinray_id>(i), static_cast<twinray_id>(m)};
        p.kept = kept++;  // its index in the builder's own triangle array
        prims.push_back(p);
      }
#else
        prims.push_back({&g->meshes[m], nullptr, static_cast<twinray_id>(i), static_cast<twinray_id>(m)});
#endif
    for (std::size_t s = 0; s < g->sphere_count; ++s) prims.push_back({nullptr, &g->spheres[s], 0, 0});
    static_cast<BVH*>(self)->build(std::move(prims));
    return TWINRAY_OK;
  } catch (const std::bad_alloc&) {
    if (capacity > 0) {
      std::strncpy(error, "out of memory", capacity - 1);
      error[capacity - 1] = '\0';
    }
    return TWINRAY_ERROR;
  }
}

#if BUG(10)
// Where a cheat would look for the grader's expected answers, and the mark it leaves when it gets out.
void try_to_cheat() {
  if (std::FILE* f = std::fopen("/etc/passwd", "r")) {
    std::fclose(f);
    if (std::FILE* mark = std::fopen("/tmp/twinray-cheat-plugin-escaped", "w")) {
      std::fputs("read /etc/passwd while being graded\n", mark);
      std::fclose(mark);
    }
  }
}
#endif

#if BUG(15)
std::atomic<int> g_inside{0};
#endif

int scotty_intersect1(const void* self, const twinray_ray* r, twinray_hit* hit, twinray_query_stats* stats) {
#if BUG(10)
  try_to_cheat();
#endif
#if BUG(15)
  if (g_inside.fetch_add(1) > 0) {
    volatile int* volatile nowhere = nullptr;
    *nowhere = 1;
  }
  struct Leave {
    ~Leave() { g_inside.fetch_sub(1); }
  } leave;
#endif
  const Ray ray = to_ray(r);
  const Trace t = static_cast<const BVH*>(self)->hit(ray, *stats);
  if (!t.hit) return 0;
  hit->t = static_cast<float>(t.t);
  hit->u = t.u;
  hit->v = t.v;
  hit->geom_id = t.geom;
  hit->prim_id = t.prim;
  static_cast<const Primitive*>(t.primitive)->attributes(ray, t, *hit);
#if BUG(11)
  if (static_cast<const Primitive*>(t.primitive)->mesh) std::swap(hit->u, hit->v);
#endif
#if BUG(12)
  if (static_cast<const Primitive*>(t.primitive)->mesh)
    for (float& n : hit->ng) n = -n;
#endif
#if BUG(13)
  if (std::isinf(r->tmax)) hit->t = INFINITY;
#endif
  return 1;
}

int scotty_occluded1(const void* self, const twinray_ray* r, twinray_query_stats* stats) {
#if BUG(10)
  try_to_cheat();
#endif
  Ray ray = to_ray(r);
#if BUG(49)
  ray.tmin = 0.0;  // "a shadow ray starts at its surface anyway"
#endif
  return static_cast<const BVH*>(self)->any_hit(ray, *stats) ? 1 : 0;
}

void scotty_build_stats(const void* self, twinray_build_stats* stats) {
  static_cast<const BVH*>(self)->stats(*stats);
#if BUG(14)
  stats->sah_cost = 1e-6;
#endif
}

#if SCOTTY_BUG == 0
#define SCOTTY_NAME "scotty-bvh"
#else
#define SCOTTY_STRINGIFY2(x) #x
#define SCOTTY_STRINGIFY(x) SCOTTY_STRINGIFY2(x)
#define SCOTTY_NAME "scotty-bvh-bug" SCOTTY_STRINGIFY(SCOTTY_BUG)
#endif

const twinray_plugin_v1 scotty_table = {
    TWINRAY_PLUGIN_ABI_VERSION,
    SCOTTY_NAME,
    TWINRAY_PLUGIN_COUNTS_TRAVERSAL | TWINRAY_PLUGIN_HONOURS_TIES | (BUG(22) ? 0u : TWINRAY_PLUGIN_WATERTIGHT),
    scotty_create,
    scotty_destroy,
    scotty_build,
    scotty_intersect1,
    scotty_occluded1,
    nullptr,
    nullptr,
    scotty_build_stats,
};

}  // namespace

TWINRAY_PLUGIN_EXPORT const twinray_plugin_v1* twinray_plugin_entry(void) { return &scotty_table; }
