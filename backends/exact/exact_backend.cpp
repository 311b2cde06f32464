#include "backends/exact/exact_backend.h"

#include "backends/bvh/bvh_builder.h"
#include "backends/exact/exact_filters.h"
#include "core/exact/exact_number.h"
#include "core/exact/exact_sphere.h"
#include "core/exact/exact_triangle.h"
#include "core/intersect/triangle_refine.h"
#include "core/intersect/triangle_watertight.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <utility>

namespace twinray {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// The float next to x toward -inf / +inf, as an exact double: a t with tmin <= round(t) <= tmax lies in
// (below(tmin), above(tmax)), which is the interval the traversal keeps.
double below(float x) { return exact::to_double_exact(std::nextafter(x, -std::numeric_limits<float>::infinity())); }
double above(float x) {
  return std::isinf(x) ? kInf : exact::to_double_exact(std::nextafter(x, std::numeric_limits<float>::infinity()));
}

// Slab test in double that never culls a box the exact line meets within [t_lo, t_hi]: each slab distance
// (plane - o) / d is two correctly rounded operations away from the exact one, a relative error below
// 2^-51, so widening it by 2^-50 of its magnitude keeps it conservative. A box grown by `margin` (itself
// widened by its rounding) gives the superset of primitives within `margin` of the segment.
bool slab(const ExactBackend::Node& node, const glm::dvec3& o, const glm::dvec3& d, double margin, double t_lo,
          double t_hi, double& entry) {
  for (int k = 0; k < 3; ++k) {
    double lo = node.lo[k], hi = node.hi[k];
    if (margin > 0.0) {
      lo -= margin;
      hi += margin;
      lo -= std::fabs(lo) * 0x1p-52;
      hi += std::fabs(hi) * 0x1p-52;
    }
    if (d[k] == 0.0) {
      if (o[k] < lo || o[k] > hi) return false;
      continue;
    }
    double near = (lo - o[k]) / d[k], far = (hi - o[k]) / d[k];
    if (near > far) std::swap(near, far);
    near -= std::fabs(near) * 0x1p-50;
    far += std::fabs(far) * 0x1p-50;
    t_lo = std::max(t_lo, near);
    t_hi = std::min(t_hi, far);
    if (t_lo > t_hi) return false;
  }
  entry = t_lo;
  return true;
}

struct PrimitiveHit {
  float t = 0.0f, u = 0.0f, v = 0.0f;
  bool far_root = false;  // spheres: the far root was taken
};

bool finite_in(float t, float tmin, float tmax) { return std::isfinite(t) && t >= tmin && t <= tmax; }

// The exact hit of one primitive with tmin <= t <= tmax (on the rounded t), sphere_robust.h's root choice.
bool test_primitive(const ExactBackend::Primitive& p, const glm::dvec3& o, const glm::dvec3& d, float tmin, float tmax,
                    PrimitiveHit& out) {
  if (p.sphere) {
    const double radius = p.dp[1].x;
    if (exact_filter::sphere_certainly_missed(o, d, p.dp[0], radius)) return false;
    const exact::SphereCrossing c = exact::intersect_sphere_exact({o, d, p.dp[0], radius});
    if (!c.real) return false;
    if (finite_in(c.t_near, tmin, tmax)) {
      out.t = c.t_near;
      out.far_root = false;
      return true;
    }
    if (finite_in(c.t_far, tmin, tmax)) {
      out.t = c.t_far;
      out.far_root = true;
      return true;
    }
    return false;
  }
  switch (exact_filter::triangle(o, d, p.dp[0], p.dp[1], p.dp[2])) {
    case exact_filter::Decision::Miss: return false;
    case exact_filter::Decision::Hit:
      return refine_triangle_hit(o, d, p.dp[0], p.dp[1], p.dp[2], tmin, tmax, out.t, out.u, out.v);
    case exact_filter::Decision::Undecided: break;
  }
  const exact::TriangleCrossing c = exact::intersect_triangle_exact({o, d, p.dp[0], p.dp[1], p.dp[2]});
  if (!c.hit || !finite_in(c.t, tmin, tmax)) return false;
  out.t = c.t;
  out.u = c.u;
  out.v = c.v;
  return true;
}

}  // namespace

void ExactBackend::build(const SceneGeometry& geometry) {
  const auto start = std::chrono::steady_clock::now();
  const std::size_t n_triangles = geometry.triangle_count();
  std::vector<Bounds3> bounds;
  std::vector<Primitive> by_id;
  bounds.reserve(geometry.primitive_count());
  by_id.reserve(geometry.primitive_count());
  for (const TriangleMesh& mesh : geometry.meshes) {
    for (std::size_t i = 0; i < mesh.indices.size(); ++i) {
      const glm::uvec3& tri = mesh.indices[i];
      Primitive p;
      p.ref = {mesh.geom_id, static_cast<std::uint32_t>(i)};
      for (int k = 0; k < 3; ++k) {
        p.p[k] = mesh.positions[tri[k]];
        p.dp[k] = exact::to_double_exact(p.p[k]);
      }
      Bounds3 b = Bounds3::of_point(p.p[0]);
      b.extend(p.p[1]);
      b.extend(p.p[2]);
      bounds.push_back(b);
      by_id.push_back(p);
    }
  }
  for (const Sphere& s : geometry.spheres) {
    Primitive p;
    p.ref = {s.geom_id, 0};
    p.sphere = true;
    p.p[0] = s.center;
    p.p[1] = glm::vec3(s.radius, 0.0f, 0.0f);
    p.dp[0] = exact::to_double_exact(s.center);
    p.dp[1] = glm::dvec3(exact::to_double_exact(s.radius), 0.0, 0.0);
    bounds.push_back(s.bounds());  // only shapes the tree; the boxes traversed are recomputed below
    by_id.push_back(p);
  }

  // The bvh backend's builder shapes the tree; its float boxes are not used.
  const BvhTree tree = build_bvh(bounds, static_cast<std::uint32_t>(n_triangles), BvhBuildOptions{});
  prims_.clear();
  prims_.reserve(tree.prim_order.size());
  for (const std::uint32_t id : tree.prim_order) prims_.push_back(by_id[id]);
  nodes_.assign(tree.nodes.size(), Node{});
  // Children follow their parent in the depth-first array, so a backward sweep sees them first.
  for (std::size_t i = tree.nodes.size(); i-- > 0;) {
    const BvhNode& src = tree.nodes[i];
    Node& node = nodes_[i];
    node.lo = glm::dvec3(kInf);
    node.hi = glm::dvec3(-kInf);
    if (src.is_leaf()) {
      node.offset = src.first_prim();
      node.count = src.prim_count();
      for (std::uint32_t k = node.offset; k < node.offset + node.count; ++k) {
        const Primitive& p = prims_[k];
        if (p.sphere) {
          // center -+ r, each one rounding away from the exact value: widened past it.
          const glm::dvec3 lo = p.dp[0] - p.dp[1].x, hi = p.dp[0] + p.dp[1].x;
          node.lo = glm::min(node.lo, lo - glm::abs(lo) * 0x1p-52);
          node.hi = glm::max(node.hi, hi + glm::abs(hi) * 0x1p-52);
        } else {
          for (int v = 0; v < 3; ++v) {
            node.lo = glm::min(node.lo, p.dp[v]);
            node.hi = glm::max(node.hi, p.dp[v]);
          }
        }
      }
    } else {
      node.offset = src.second_child();
      const Node& a = nodes_[i + 1];
      const Node& b = nodes_[node.offset];
      node.lo = glm::min(a.lo, b.lo);
      node.hi = glm::max(a.hi, b.hi);
    }
  }

  stats_ = BuildStats{};
  stats_.triangles = n_triangles;
  stats_.spheres = geometry.sphere_count();
  stats_.built_triangles = geometry.has_triangles();
  stats_.built_spheres = geometry.has_spheres();
  stats_.nodes = nodes_.size();
  stats_.leaves = tree.leaves;
  stats_.max_depth = tree.max_depth;
  stats_.memory_bytes = nodes_.capacity() * sizeof(Node) + prims_.capacity() * sizeof(Primitive);
  stats_.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

template <class Visit>
void ExactBackend::traverse(const glm::dvec3& o, const glm::dvec3& d, double margin, double t_lo, double& t_hi,
                            Visit&& visit, QueryStats* stats) const {
  if (nodes_.empty()) return;
  struct Entry {
    std::uint32_t node;
    double entry;
  };
  Entry stack[kBvhMaxDepth + 1];
  std::size_t size = 0;
  double entry = 0.0;
  std::uint64_t visited = 1;
  if (slab(nodes_[0], o, d, margin, t_lo, t_hi, entry)) {
    std::uint32_t index = 0;
    for (;;) {
      const Node& node = nodes_[index];
      bool descended = false;
      if (node.count != 0) {
        bool go_on = true;
        for (std::uint32_t k = node.offset; k < node.offset + node.count && go_on; ++k) go_on = visit(prims_[k]);
        if (!go_on) break;
      } else {
        visited += 2;
        const std::uint32_t left = index + 1, right = node.offset;
        double entry_left = 0.0, entry_right = 0.0;
        const bool hit_left = slab(nodes_[left], o, d, margin, t_lo, t_hi, entry_left);
        const bool hit_right = slab(nodes_[right], o, d, margin, t_lo, t_hi, entry_right);
        if (hit_left && hit_right) {
          const bool left_first = entry_left <= entry_right;
          stack[size++] = left_first ? Entry{right, entry_right} : Entry{left, entry_left};
          index = left_first ? left : right;
          descended = true;
        } else if (hit_left || hit_right) {
          index = hit_left ? left : right;
          descended = true;
        }
      }
      if (descended) continue;
      bool popped = false;
      while (size > 0 && !popped) {
        const Entry& e = stack[--size];
        if (e.entry <= t_hi) {
          index = e.node;
          popped = true;
        }
      }
      if (!popped) break;
    }
  }
  if (stats) stats->nodes_visited += visited;
}

bool ExactBackend::intersect(const Ray& ray, Hit& hit, QueryStats* stats) const {
  hit = Hit{};
  if (stats) ++stats->queries;
  if (!is_valid_ray(ray)) return false;
  const glm::dvec3 o = exact::to_double_exact(ray.org), d = exact::to_double_exact(ray.dir);
  float tmax = ray.tmax;
  double t_hi = above(tmax);
  const Primitive* best = nullptr;
  bool best_far_root = false;
  traverse(o, d, 0.0, below(ray.tmin), t_hi,
           [&](const Primitive& p) {
             if (stats) ++stats->primitives_tested;
             PrimitiveHit h;
             // tmax = the best t so far (closed): an equal t still reaches `precedes`.
             if (!test_primitive(p, o, d, ray.tmin, tmax, h)) return true;
             if (!precedes(h.t, p.ref.geom_id, p.ref.prim_id, hit)) return true;
             hit.t = tmax = h.t;
             hit.u = h.u;
             hit.v = h.v;
             hit.geom_id = p.ref.geom_id;
             hit.prim_id = p.ref.prim_id;
             best = &p;
             best_far_root = h.far_root;
             t_hi = above(tmax);
             return true;
           },
           stats);
  if (best == nullptr) return false;
  if (best->sphere) {
    exact::sphere_attributes_exact({o, d, best->dp[0], best->dp[1].x}, best_far_root, hit.ng, hit.u, hit.v);
  } else {
    hit.ng = triangle_geometric_normal(best->p[0], best->p[1], best->p[2]);
  }
  return true;
}

bool ExactBackend::occluded(const Ray& ray, QueryStats* stats) const {
  if (stats) ++stats->queries;
  if (!is_valid_ray(ray)) return false;
  const glm::dvec3 o = exact::to_double_exact(ray.org), d = exact::to_double_exact(ray.dir);
  double t_hi = above(ray.tmax);
  bool found = false;
  traverse(o, d, 0.0, below(ray.tmin), t_hi,
           [&](const Primitive& p) {
             if (stats) ++stats->primitives_tested;
             PrimitiveHit h;
             found = test_primitive(p, o, d, ray.tmin, ray.tmax, h);
             return !found;
           },
           stats);
  return found;
}

void ExactBackend::primitives_near(const Ray& ray, double margin, double t_lo, double t_hi,
                                   std::vector<PrimitiveRef>& out) const {
  const glm::dvec3 o = exact::to_double_exact(ray.org), d = exact::to_double_exact(ray.dir);
  traverse(o, d, margin, t_lo, t_hi,
           [&](const Primitive& p) {
             out.push_back(p.ref);
             return true;
           },
           nullptr);
}

std::unique_ptr<Backend> make_exact_backend() { return std::make_unique<ExactBackend>(); }

}  // namespace twinray
