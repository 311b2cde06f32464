// build: the plugin builds the scene within the check's time and memory limits (enforced by the worker), and
// the tree it built answers a few probe rays like the reference: a builder that drops primitives, or that
// never stops splitting identical boxes, is caught here rather than in every later check.

#include "harness/grade/answers.h"
#include "harness/grade/checks.h"

#include <fmt/core.h>


namespace twinray::grade {

namespace {
constexpr std::size_t kDefaultProbeRays = 256;
}

CheckVerdict run_build_check(CheckContext& ctx) {
  const SceneGeometry& geometry = ctx.scene.geometry();
  double wall = 0.0;
  PluginInstance plugin = ctx.built_plugin(&wall);
  const BuildStats stats = plugin->build_stats();

  const std::vector<Ray> rays = ctx.rays_of_kinds({crosscheck::RayKind::Uniform}, ctx.count_or(kDefaultProbeRays));
  const Answers mine = trace_rays(*plugin, rays, Queries::Both);
  plugin.end();
  const Answers expected = trace_rays(ctx.scene.reference(ctx.reference_name()), rays, Queries::Both);
  const Judgement j = judge(ctx.scene, rays, mine, expected,
                            {Queries::Both, ctx.reference_name(), ctx.env.plugin.traits().honours_ties, "plugin",
                             ctx.env.plugin.traits().watertight});

  CheckVerdict v;
  v.figures = {{"build_seconds", stats.build_seconds},
               {"wall_seconds", wall},
               {"triangles", geometry.triangle_count()},
               {"spheres", geometry.sphere_count()},
               {"memory_bytes", stats.memory_bytes},
               {"nodes", stats.nodes},
               {"probe_rays", rays.size()},
               {"wrong", j.wrong_total()}};
  const std::string built = fmt::format("built {} triangles, {} spheres in {:.3f} s", geometry.triangle_count(),
                                        geometry.sphere_count(), stats.build_seconds);
  v.passed = j.wrong_total() == 0;
  if (v.passed) {
    v.detail = fmt::format("{}; {} probe rays answered right", built, rays.size());
  } else {
    const WrongAnswer& first = j.wrong.front();
    v.detail = fmt::format("{}, but {} of {} probe answers are wrong; first, ray {}: {}", built, j.wrong_total(),
                           2 * rays.size(), first.ray, j.first_wrong_description);
    v.reproduce = ctx.trace_command(rays[first.ray]);
    ctx.confirm_replay(v, rays[first.ray], first.any_hit, mine.hits[first.ray], mine.occluded[first.ray] != 0);
  }
  return v;
}

}  // namespace twinray::grade
