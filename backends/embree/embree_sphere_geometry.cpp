#include "backends/embree/embree_sphere_geometry.h"

#include "core/intersect/sphere_robust.h"

#include <glm/vec3.hpp>

#include <cmath>
#include <limits>

namespace twinray {

namespace {

// Bounds rounded outward by one ulp: center -/+ radius in float may round toward the center by half an
// ulp, and the double-precision routine finds hits on the exact sphere, just outside such a box, that the
// box test would then cull.
void sphere_bounds(const RTCBoundsFunctionArguments* args) {
  const Sphere& s = static_cast<const Sphere*>(args->geometryUserPtr)[args->primID];
  constexpr float kInf = std::numeric_limits<float>::infinity();
  RTCBounds& b = *args->bounds_o;
  b.lower_x = std::nextafter(s.center.x - s.radius, -kInf);
  b.lower_y = std::nextafter(s.center.y - s.radius, -kInf);
  b.lower_z = std::nextafter(s.center.z - s.radius, -kInf);
  b.upper_x = std::nextafter(s.center.x + s.radius, kInf);
  b.upper_y = std::nextafter(s.center.y + s.radius, kInf);
  b.upper_z = std::nextafter(s.center.z + s.radius, kInf);
}

glm::vec3 ray_origin(RTCRayN* ray, unsigned n, unsigned i) {
  return {RTCRayN_org_x(ray, n, i), RTCRayN_org_y(ray, n, i), RTCRayN_org_z(ray, n, i)};
}
glm::vec3 ray_direction(RTCRayN* ray, unsigned n, unsigned i) {
  return {RTCRayN_dir_x(ray, n, i), RTCRayN_dir_y(ray, n, i), RTCRayN_dir_z(ray, n, i)};
}

// Embree hands over N rays (N = 1 for the single-ray and stream APIs twinray uses, but the contract allows
// packets) with a validity mask: -1 valid, 0 inactive.
void sphere_intersect(const RTCIntersectFunctionNArguments* args) {
  const Sphere& s = static_cast<const Sphere*>(args->geometryUserPtr)[args->primID];
  const unsigned n = args->N;
  RTCRayN* ray = RTCRayHitN_RayN(args->rayhit, n);
  RTCHitN* hit = RTCRayHitN_HitN(args->rayhit, n);
  for (unsigned i = 0; i < n; ++i) {
    if (args->valid[i] == 0) continue;
    float t = 0.0f;
    // The current tfar is the closest hit so far: only a closer (or equally close) root replaces it.
    if (!intersect_sphere(ray_origin(ray, n, i), ray_direction(ray, n, i), s.center, s.radius,
                          RTCRayN_tnear(ray, n, i), RTCRayN_tfar(ray, n, i), t))
      continue;
    RTCRayN_tfar(ray, n, i) = t;
    // Ng, u and v are recomputed by the backend for the final hit only; zero them so no stale value of
    // a previous candidate survives.
    RTCHitN_Ng_x(hit, n, i) = 0.0f;
    RTCHitN_Ng_y(hit, n, i) = 0.0f;
    RTCHitN_Ng_z(hit, n, i) = 0.0f;
    RTCHitN_u(hit, n, i) = 0.0f;
    RTCHitN_v(hit, n, i) = 0.0f;
    RTCHitN_primID(hit, n, i) = args->primID;
    RTCHitN_geomID(hit, n, i) = args->geomID;
    RTCHitN_instID(hit, n, i, 0) = args->context->instID[0];
  }
}

void sphere_occluded(const RTCOccludedFunctionNArguments* args) {
  const Sphere& s = static_cast<const Sphere*>(args->geometryUserPtr)[args->primID];
  const unsigned n = args->N;
  for (unsigned i = 0; i < n; ++i) {
    if (args->valid[i] == 0) continue;
    float t = 0.0f;
    if (intersect_sphere(ray_origin(args->ray, n, i), ray_direction(args->ray, n, i), s.center, s.radius,
                         RTCRayN_tnear(args->ray, n, i), RTCRayN_tfar(args->ray, n, i), t))
      RTCRayN_tfar(args->ray, n, i) = -std::numeric_limits<float>::infinity();  // Embree's "occluded" mark
  }
}

}  // namespace

RTCGeometry create_sphere_user_geometry(RTCDevice device, std::span<const Sphere> spheres) {
  RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_USER);
  if (geometry == nullptr) return nullptr;  // the device's error callback has the reason
  rtcSetGeometryUserPrimitiveCount(geometry, static_cast<unsigned>(spheres.size()));
  // The pointer is only read; Embree's API has no const user pointer.
  void* user = const_cast<Sphere*>(spheres.data());
  rtcSetGeometryUserData(geometry, user);
  rtcSetGeometryBoundsFunction(geometry, &sphere_bounds, user);
  rtcSetGeometryIntersectFunction(geometry, &sphere_intersect);
  rtcSetGeometryOccludedFunction(geometry, &sphere_occluded);
  rtcSetGeometryBuildQuality(geometry, RTC_BUILD_QUALITY_MEDIUM);
  rtcCommitGeometry(geometry);
  return geometry;
}

}  // namespace twinray
