// watertight: rays that must hit a closed mesh (from inside it, exactly through its vertices and edges, and
// from outside at its vertices; grade_rays.h). A miss is a leak, with no ambiguity: whatever triangle
// owns an edge, one of them must report the ray. Rays the reference itself lets through (a scene that is
// not closed) are left out and counted.

#include "harness/grade/answers.h"
#include "harness/grade/checks.h"
#include "harness/grade/grade_rays.h"

#include <fmt/core.h>

namespace twinray::grade {

namespace {
constexpr std::size_t kDefaultRays = 20000;
}

CheckVerdict run_watertight_check(CheckContext& ctx) {
  const std::size_t count = ctx.spec.count != 0 ? ctx.spec.count : kDefaultRays;
  const std::vector<Ray> rays = watertight_rays(ctx.scene.scene(), count, ctx.spec.seed, ctx.spec.origin);
  PluginInstance plugin = ctx.built_plugin();
  const Answers mine = trace_rays(*plugin, rays, Queries::Both);
  plugin.end();
  const Answers expected = trace_rays(ctx.scene.reference("embree"), rays, Queries::Both);

  std::size_t leaks_closest = 0, leaks_any = 0, reference_leaks = 0;
  std::optional<std::size_t> first;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    if (!expected.hits[i].found() || !expected.occluded[i]) {
      ++reference_leaks;
      continue;
    }
    const bool closest_leak = !mine.hits[i].found(), any_leak = mine.occluded[i] == 0;
    leaks_closest += closest_leak ? 1 : 0;
    leaks_any += any_leak ? 1 : 0;
    if ((closest_leak || any_leak) && !first) first = i;
  }
  const std::size_t judged = rays.size() - reference_leaks;

  CheckVerdict v;
  v.passed = leaks_closest + leaks_any == 0;
  v.figures = {{"rays", rays.size()},
               {"judged", judged},
               {"leaks_closest", leaks_closest},
               {"leaks_any", leaks_any},
               {"reference_leaks", reference_leaks}};
  if (v.passed) {
    v.detail = fmt::format("no leak in {} rays that must hit the closed mesh (closest and any-hit)", judged);
  } else {
    v.detail = fmt::format("{} of {} rays leak through the closed mesh ({} closest-hit, {} any-hit misses); first, ray {}",
                           std::max(leaks_closest, leaks_any), judged, leaks_closest, leaks_any, *first);
    v.reproduce = ctx.trace_command(rays[*first]);
    const bool closest_leak = !mine.hits[*first].found();
    ctx.confirm_replay(v, rays[*first], !closest_leak, mine.hits[*first], mine.occluded[*first] != 0);
  }
  return v;
}

}  // namespace twinray::grade
