#pragma once
// The two kinds of primitive twinray sends: triangles and spheres. Their intersection routines are given;
// the BVH is your part.

#include "bbox.h"
#include "ray.h"

#include <cstdint>

struct Triangle {
  Vec3 p0, p1, p2;  // counter-clockwise seen from the front
  std::uint32_t geom_id = 0, prim_id = 0;

  BBox bbox() const;
  // The hit with dist_bounds[0] <= t <= dist_bounds[1], if any (Moller-Trumbore, in double precision).
  Trace hit(const Ray& ray) const;
};

struct Sphere {
  Vec3 center;
  float radius = 1.0f;
  std::uint32_t geom_id = 0;  // prim_id is always 0

  BBox bbox() const;
  // The nearest hit with dist_bounds[0] <= t <= dist_bounds[1], if any (u = phi / 2pi, v = theta / pi).
  Trace hit(const Ray& ray) const;
};

// One primitive of either kind, what the BVH stores.
struct Primitive {
  enum class Kind { Triangle, Sphere } kind = Kind::Triangle;
  Triangle triangle;
  Sphere sphere;

  BBox bbox() const { return kind == Kind::Triangle ? triangle.bbox() : sphere.bbox(); }
  Trace hit(const Ray& ray) const { return kind == Kind::Triangle ? triangle.hit(ray) : sphere.hit(ray); }
};
