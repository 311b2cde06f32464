#pragma once
// What every integrator shares: settings, the read-only scene context, per-thread counters, and the
// interface the renderer calls once per camera sample.
//
// Depth convention (Mitsuba 3): max_depth counts path segments, the camera ray being the first.
//   1 = only emitters seen directly, 2 = plus direct lighting, -1 = unlimited (Russian roulette ends paths,
//   see russian_roulette.h).
// A shadow ray counts as the segment it completes: light sampling at the vertex reached by segment k
// happens only when k + 1 <= max_depth.

#include "core/backend/backend.h"
#include "core/geometry/ray.h"
#include "core/lights/area_lights.h"
#include "core/lights/environment_light.h"
#include "core/materials/bsdf.h"
#include "core/sampling/sampler.h"
#include "core/scene/scene.h"

#include <glm/vec3.hpp>

#include <cstdint>
#include <string_view>
#include <vector>

namespace twinray {

enum class IntegratorKind { Direct, Path };
// Which estimators contribute (for convergence studies; `Mis` is the one to use):
//   Mis   light sampling and BSDF sampling, combined with the power heuristic;
//   Bsdf  BSDF sampling only (emission found by chance is counted fully);
//   Light light sampling only wherever a light can be sampled; emission reached by BSDF sampling still
//         counts after specular bounces and on the camera ray (no light sample can produce those paths).
enum class SamplingStrategy { Mis, Bsdf, Light };

std::string_view to_string(IntegratorKind k);
std::string_view to_string(SamplingStrategy s);

struct IntegratorSettings {
  int max_depth = -1;  // see the depth convention above
  int rr_depth = 5;    // Russian roulette from this many segments on (Mitsuba's rr_depth)
  SamplingStrategy strategy = SamplingStrategy::Mis;
};

// Everything an integrator reads. Built once per render, shared by all threads.
struct SceneContext {
  const Scene* scene = nullptr;
  const Backend* backend = nullptr;
  const EnvironmentLight* environment = nullptr;  // null: rays that escape carry no radiance
  const LightSampler* lights = nullptr;           // null: no light sampling (scene has no emitters)
  std::vector<Bsdf> bsdf_of_geom;                 // per geometry id
  // Where the geometry of each id lives: index into scene->geometry.meshes or .spheres.
  struct ShapeRef {
    bool sphere = false;
    std::uint32_t index = 0;
  };
  std::vector<ShapeRef> shape_of_geom;

  static SceneContext make(const Scene& scene, const Backend& backend, const EnvironmentLight* environment,
                           const LightSampler* lights);
};

// Per-thread tallies, merged by the renderer.
struct TraceCounters {
  std::uint64_t closest_hit_rays = 0;
  std::uint64_t shadow_rays = 0;
  QueryStats query;  // filled only when `collect_query_stats` (backends that count traversal)
  bool collect_query_stats = false;

  QueryStats* query_stats() { return collect_query_stats ? &query : nullptr; }
};

// What the camera ray's first hit looked like, for the auxiliary images.
struct FirstHitInfo {
  bool hit = false;
  glm::vec3 normal{0.0f};  // geometric normal, flipped toward the camera
  glm::vec3 albedo{0.0f};
  float depth = 0.0f;      // distance along the (unit) camera ray
};

class Integrator {
 public:
  virtual ~Integrator() = default;
  virtual IntegratorKind kind() const = 0;
  // Radiance arriving along `camera_ray` (unit direction). `first`, when not null, receives the first hit.
  virtual glm::vec3 radiance(const Ray& camera_ray, Sampler& sampler, TraceCounters& counters,
                             FirstHitInfo* first) const = 0;
};

}  // namespace twinray
