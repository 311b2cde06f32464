// The wavefront path tracer (core/render/path_integrator.h) advances a batch of paths together; every
// sample must still get exactly the radiance it gets when traced alone, whatever the batch size (batches
// larger than PathIntegrator::kMaxBatch are traced in chunks), with path splitting too.

#include "render_test_util.h"

#include "core/camera/pinhole_camera.h"
#include "core/render/path_integrator.h"
#include "core/scene/scene_loader.h"

#include <gtest/gtest.h>

#include <cstring>
#include <vector>

namespace twinray {
namespace {

using namespace twinray::test;

// Bit patterns, so that -0 and NaN compare the way the film would see them.
std::array<std::uint32_t, 3> bits(const glm::vec3& v) {
  std::array<std::uint32_t, 3> b{};
  std::memcpy(b.data(), &v, sizeof b);
  return b;
}

TEST(PathWavefront, BatchesGiveEachSampleItsLonePathRadiance) {
  // Mirror, glass, diffuse and an emitter: every BSDF kind and both kinds of shape.
  Scene scene = load_scene(std::filesystem::path(TWINRAY_SOURCE_DIR) / "scenes/cornell-mirror-glass.json");
  const ScopedFlushDenormals ftz;
  const std::unique_ptr<Backend> backend = built_backend(scene, "bvh8");
  RenderOptions opt;
  const RenderSetup setup(scene, opt, backend->traits());
  const SceneContext ctx = SceneContext::make(scene, *backend, setup.environment(), setup.lights());
  const PinholeCamera camera(scene.camera);

  for (const SamplerKind kind : {SamplerKind::Sobol, SamplerKind::Sobol4d})
  for (const int max_depth : {-1, 6})
  for (const auto& [splits, connections] : {std::pair{1u, 0u}, std::pair{3u, 0u}, std::pair{3u, 2u}}) {
    IntegratorSettings settings;
    settings.max_depth = max_depth;
    settings.splits = splits;
    settings.light_connections = connections;
    const PathIntegrator integrator(ctx, settings);
    // 300 samples: one full chunk of 256 and a partial one; several samples per pixel of a 10 x 10 patch
    // around the glass ball.
    constexpr std::size_t kSamples = 300;
    std::vector<CameraSample> batch, lone;
    for (std::size_t k = 0; k < kSamples; ++k) {
      const int x = 150 + static_cast<int>(k % 10), y = 180 + static_cast<int>((k / 10) % 10);
      Sampler sampler(kind, 7, static_cast<std::uint64_t>(y * camera.width() + x),
                      static_cast<std::uint32_t>(k / 100));
      const glm::vec2 jitter = sampler.next_2d();
      const Ray ray = camera.generate_ray((static_cast<float>(x) + jitter.x) / static_cast<float>(camera.width()),
                                          1.0f - (static_cast<float>(y) + jitter.y) / static_cast<float>(camera.height()));
      batch.push_back(CameraSample{ray, sampler});
    }
    lone = batch;
    std::vector<glm::vec3> out(kSamples);
    std::vector<FirstHitInfo> first(kSamples);
    TraceCounters batch_counters, lone_counters;
    integrator.radiance(std::span(batch), std::span(out), std::span(first), batch_counters);
    std::size_t nonzero = 0;
    for (std::size_t k = 0; k < kSamples; ++k) {
      FirstHitInfo lone_first;
      const glm::vec3 L = integrator.radiance(lone[k].ray, lone[k].sampler, lone_counters, &lone_first);
      EXPECT_EQ(bits(out[k]), bits(L)) << "sample " << k << ", max depth " << max_depth << ", " << to_string(kind) << ", splits " << splits << ", light connections " << connections;
      EXPECT_EQ(first[k].hit, lone_first.hit);
      EXPECT_EQ(bits(first[k].normal), bits(lone_first.normal));
      EXPECT_EQ(first[k].depth, lone_first.depth);
      nonzero += L.x > 0.0f ? 1 : 0;
    }
    EXPECT_GT(nonzero, kSamples / 2) << "the patch should be lit";
    EXPECT_EQ(batch_counters.closest_hit_rays, lone_counters.closest_hit_rays);
    EXPECT_EQ(batch_counters.shadow_rays, lone_counters.shadow_rays);
  }
}

}  // namespace
}  // namespace twinray
