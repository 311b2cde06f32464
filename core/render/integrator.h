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
#include "core/render/triangle_surface.h"
#include "core/sampling/sampler.h"
#include "core/scene/scene.h"

#include <glm/vec3.hpp>

#include <cstdint>
#include <span>
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

// Largest IntegratorSettings::splits the commands accept (more only multiplies the work per camera sample).
inline constexpr std::uint32_t kMaxSplits = 16;

struct IntegratorSettings {
  int max_depth = -1;  // see the depth convention above
  int rr_depth = 5;    // Russian roulette from this many segments on (Mitsuba's rr_depth)
  SamplingStrategy strategy = SamplingStrategy::Mis;
  // The light tracer (core/render/light_tracer.h) counts the caustic paths E x1 ... S+ L (x1 non-delta,
  // the vertices after the last non-delta one all delta): the path tracer then leaves them out.
  bool light_traced_caustics = false;
  // Path splitting: a path continues `splits` times from its first non-delta vertex (each continuation
  // carrying 1/splits of the throughput, each with its own Sampler::split), sharing the segments up to that
  // vertex and its light sample. 1: no splitting. 4 (the default) takes 24% off time x relMSE on the Cornell
  // box at equal samples per pixel and adds 8% on the mirror-and-glass box (docs/rendering.md#path-splitting).
  std::uint32_t splits = 4;
  // Light connections (core/render/light_connection.h): per camera sample this many light subpaths of one
  // segment start on the surface lights, and the path's non-delta vertices up to kLightConnectionMaxDepth
  // segments deep are joined to their first non-delta hits, MIS weighted against the path tracer's two ways
  // to the same paths. 0: none. Only with the Mis strategy and max_depth unlimited or at least 3 (the path
  // integrator turns them off otherwise). 1 (the default) takes 12% off instructions x relMSE on the Cornell
  // box and adds 14% on the mirror-and-glass box (docs/rendering.md#light-connections).
  std::uint32_t light_connections = 1;
};

// Largest IntegratorSettings::light_connections the commands accept.
inline constexpr std::uint32_t kMaxLightConnections = 4;

// What a hit needs to know about the surface of one geometry id, gathered once per render so that shading
// a hit costs one table lookup (not shape -> material -> BSDF).
struct GeomShading {
  Bsdf bsdf;
  glm::vec3 emission{0.0f};  // radiance an emissive material sends from its front side; 0 otherwise
  bool emissive = false;
  bool sphere = false;       // where the geometry lives: scene->geometry.spheres or .meshes ...
  std::uint32_t shape = 0;   // ... at this index
  std::uint32_t first_triangle = 0;  // meshes: where the mesh's triangles start in SceneContext::triangles
};

// Everything an integrator reads. Built once per render, shared by all threads.
struct SceneContext {
  const Scene* scene = nullptr;
  const Backend* backend = nullptr;
  const EnvironmentLight* environment = nullptr;  // null: rays that escape carry no radiance
  const LightSampler* lights = nullptr;           // null: no light sampling (scene has no emitters)
  std::vector<GeomShading> geoms;                 // per geometry id
  // Every mesh triangle, mesh after mesh (GeomShading::first_triangle + prim_id): what turns a closest hit's
  // t and ids into a surface point, so that the integrators ask the backend for t and ids only.
  std::vector<TriangleSurface> triangles;

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

// One camera sample: its ray and the sampler that draws all of its random numbers.
struct CameraSample {
  Ray ray;          // unit direction
  Sampler sampler;  // already past the camera's own dimensions
};

class Integrator {
 public:
  virtual ~Integrator() = default;
  virtual IntegratorKind kind() const = 0;
  // Radiance arriving along `camera_ray` (unit direction). `first`, when not null, receives the first hit.
  virtual glm::vec3 radiance(const Ray& camera_ray, Sampler& sampler, TraceCounters& counters,
                             FirstHitInfo* first) const = 0;
  // The same for a batch of camera samples: out[i] (and first[i], when `first` is not empty) receives what
  // radiance() would return for samples[i], bit for bit. The renderer hands over one sample of every pixel
  // of a tile at a time; an integrator that can advance many paths together (the path integrator) overrides
  // this, the default calls radiance() for each sample in turn.
  virtual void radiance(std::span<CameraSample> samples, std::span<glm::vec3> out, std::span<FirstHitInfo> first,
                        TraceCounters& counters) const;
};

}  // namespace twinray
