#pragma once
// All spheres of a scene as one Embree user geometry whose callbacks run twinray's own sphere routine.
//
// Why a user geometry rather than RTC_GEOMETRY_TYPE_SPHERE_POINT: the native point-sphere intersector
// works in float; on a sphere of radius 1e5 seen from 3 units away its t is off by 2.6e-3 (relative: some
// 30000 float ulps), as measured by tests/test_embree_backend.cpp (docs/embree-backend.md), while
// core/intersect/sphere_robust.h works in double, stays within one float ulp, and is the routine every
// other backend calls. With the same sphere arithmetic on both sides, a crosscheck difference on a sphere
// can only be a traversal difference.
// The price is an indirect call per candidate sphere, which only sphere-heavy scenes notice.
//
// Identity: Embree sees one geometry whose primitive i is spheres[i]; the backend maps a hit on primitive
// i back to spheres[i].geom_id with prim_id 0 (scene_geometry.h). The callbacks only find t; normal and
// (u,v) are computed once for the final hit by the backend, not for every candidate.

#include "core/geometry/scene_geometry.h"

#include <embree3/rtcore.h>

#include <span>

namespace twinray {

// A committed user geometry over `spheres`, which must outlive it (the callbacks read it in place).
// The caller attaches it to its scene and releases it.
RTCGeometry create_sphere_user_geometry(RTCDevice device, std::span<const Sphere> spheres);

}  // namespace twinray
