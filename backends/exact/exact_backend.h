#pragma once
// The `exact` backend: the true closest hit, from the float ray and float vertices taken as exact numbers.
//
// Every primitive the ray could touch is decided in exact arithmetic (core/exact/): triangles by the fill
// rule of the watertight test evaluated in the exact sheared frame, spheres by the exact sign of the
// discriminant. t, u, v are correctly rounded to float (triangles through core/intersect/triangle_refine.h,
// whose double path is certified by an error bound and falls back to GMP; spheres by Ziv's strategy in
// MPFR). The answer then follows the contract every backend is held to, on the reported floats: a hit counts
// when tmin <= t <= tmax, and the closest is the least by `precedes` (t, then geom_id, then prim_id). So it is
// the answer a perfect float backend must give, unique on shared edges and vertices, and equal bit for bit
// to bvh and brute wherever their float edge test agrees with the exact one. docs/exact-backend.md.
//
// Slow by design but usable on any scene: a double-precision filter with a rigorous error bound decides
// most primitives (certain miss, or certain interior hit) without GMP, and a BVH (the bvh backend's builder)
// whose boxes are recomputed in double, and whose slab test widens every distance by more than its
// rounding error, never culls a primitive the exact ray touches. Thread-safe: GMP and MPFR objects live on
// the stack of each call, nothing is shared after build. Independent of flush-to-zero and
// denormals-are-zero: floats are converted to double through their bits.

#include "core/backend/backend.h"

#include <glm/vec3.hpp>

#include <cstdint>
#include <memory>
#include <vector>

namespace twinray {

struct PrimitiveRef {
  std::uint32_t geom_id = 0;
  std::uint32_t prim_id = 0;
  bool operator==(const PrimitiveRef&) const = default;
};

class ExactBackend final : public Backend {
 public:
  std::string_view name() const override { return "exact"; }
  BackendTraits traits() const override {
    return {.counts_traversal = true, .honours_ties = true, .watertight = true};
  }

  void build(const SceneGeometry& geometry) override;
  BuildStats build_stats() const override { return stats_; }

  bool intersect(const Ray& ray, Hit& hit, QueryStats* stats = nullptr) const override;
  bool occluded(const Ray& ray, QueryStats* stats = nullptr) const override;
  using Backend::intersect;
  using Backend::occluded;

  // For the arbiter: appends every primitive whose bounding box, grown by `margin` (world units) on every
  // side, the ray's line meets at some t in [t_lo, t_hi]: a superset of the primitives that come within
  // `margin` of that segment. Works on any ray with a finite origin and a non-zero finite direction.
  void primitives_near(const Ray& ray, double margin, double t_lo, double t_hi, std::vector<PrimitiveRef>& out) const;

  // The flat tree and the primitives in leaf order (public only for the helpers of exact_backend.cpp).
  struct Node {
    glm::dvec3 lo, hi;        // exact (triangles) or outward-rounded (spheres) bounds of the subtree
    std::uint32_t offset = 0;  // interior: index of the second child; leaf: first primitive
    std::uint32_t count = 0;   // interior: 0; leaf: number of primitives
  };
  struct Primitive {
    PrimitiveRef ref;
    bool sphere = false;
    glm::vec3 p[3];      // triangle vertices, or sphere center in p[0] and radius in p[1].x, as given
    glm::dvec3 dp[3];    // the same, exactly, in double
  };

 private:
  template <class Visit>
  void traverse(const glm::dvec3& o, const glm::dvec3& d, double margin, double t_lo, double& t_hi, Visit&& visit,
                QueryStats* stats) const;

  std::vector<Node> nodes_;
  std::vector<Primitive> prims_;  // in leaf order
  BuildStats stats_;
};

std::unique_ptr<Backend> make_exact_backend();

}  // namespace twinray
