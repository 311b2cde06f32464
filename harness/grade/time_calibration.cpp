#include "harness/grade/time_calibration.h"

#include "backends/registry.h"
#include "core/sampling/rng.h"
#include "harness/scenes/named_scene.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <vector>

namespace twinray::grade {

namespace {

constexpr int kRuns = 5;
constexpr std::size_t kRays = 50000;
constexpr double kNoise = 1.25;
constexpr std::array kLadder = {1.0, 1.5, 2.0, 3.0, 4.0, 6.0, 8.0, 12.0, 16.0, 24.0, 32.0, 48.0, 64.0, 100.0};

// Segments between two random points of [-1.2, 1.2]^3 (the soup fills [-1, 1]^3): a fixed, varied load.
std::vector<Ray> workload_rays() {
  Rng rng = Rng::keyed(1, 0x7157, 3);
  const auto coordinate = [&] { return -1.2f + 2.4f * rng.next_float(); };
  std::vector<Ray> rays(kRays);
  for (Ray& r : rays) {
    const glm::vec3 a{coordinate(), coordinate(), coordinate()}, b{coordinate(), coordinate(), coordinate()};
    r.org = a;
    r.dir = b - a;
    r.tmin = 0.0f;
    r.tmax = 1.0f;
  }
  return rays;
}

}  // namespace

double quantised_time_scale(double ratio) {
  const double wanted = ratio / kNoise;
  for (const double rung : kLadder)
    if (rung >= wanted) return rung;
  return kLadder.back();
}

TimeCalibration calibrate_time_scale() {
  const Scene scene = load_named_scene("procedural:soup:10000:1");
  const std::vector<Ray> rays = workload_rays();
  std::vector<Hit> hits(rays.size());
  std::array<double, kRuns> seconds{};
  for (double& s : seconds) {
    const auto start = std::chrono::steady_clock::now();
    const std::unique_ptr<Backend> bvh = make_backend("bvh");
    bvh->build(scene.geometry);
    bvh->intersect(rays, std::span<Hit>(hits));
    s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  std::nth_element(seconds.begin(), seconds.begin() + kRuns / 2, seconds.end());
  TimeCalibration c;
  c.reference_seconds = kReferenceWorkloadSeconds;
  c.measured_seconds = seconds[kRuns / 2];
  c.scale = quantised_time_scale(c.measured_seconds / c.reference_seconds);
  return c;
}

}  // namespace twinray::grade
