// The checks that compare answers with a reference, ray by ray (answers.h says what counts as wrong):
//   closest-hit   closest hits of camera, uniform and diffuse rays; with an "origin", of rays from that point
//                 at interior points of the triangles (a distant viewpoint)
//   any-hit       any-hit answers of shadow (and other) rays
//   ray-interval  the same rays cut just before and just after their first surface (grade_rays.h), and rays
//                 whose interval ends exactly at a crossing every float test computes exactly (or one float
//                 short of it), judged strictly: the closed ends count, one float beyond does not
//   axis-aligned  rays with +0/-0 direction components and origins on the bounding box's faces
//   spheres       rays at spheres from outside, inside, near and at the tangent
//   ties          rays at exactly duplicated triangles, judged by the tie rule (hit.h) whether or not the
//                 plugin claims it (the suite decides, with "required": "if-claimed", whether it counts)
//   deep-tree     rays from a point at the triangles of a scene nested around it (procedural:nest), every
//                 order of magnitude of distance equally often: a tree as deep as the nesting, one pending
//                 entry per level, the closest hit among the last pushed (a fixed traversal stack that drops)

#include "core/util/input_error.h"
#include "harness/grade/answers.h"
#include "harness/grade/checks.h"
#include "harness/grade/disagreement_image.h"
#include "harness/grade/grade_rays.h"
#include "harness/grade/interval_ends.h"

#include <fmt/core.h>

#include <algorithm>
#include <optional>

namespace twinray::grade {

namespace {

// Default ray counts when the suite gives none ("count"): per kind for closest-hit and any-hit.
constexpr std::size_t kDefaultKindRays = 65536;
constexpr std::size_t kDefaultSpecialRays = 20000;

struct RaySet {
  std::vector<Ray> rays;
  Queries queries = Queries::Both;
  int image_width = 0, image_height = 0;  // > 0: rays [0, w*h) are the pixels of an image
  std::vector<IntervalEndRay> ends;       // ray-interval: rays that end exactly at a crossing, judged strictly
};

[[noreturn]] void suite_error(const CheckContext& ctx, const std::string& message) {
  throw InputError(ctx.env.suite.manifest, "", fmt::format("check '{}': {}", ctx.spec.name, message));
}

RaySet rays_for(CheckContext& ctx) {
  const CheckSpec& spec = ctx.spec;
  const Scene& scene = ctx.scene.scene();
  const std::size_t count = ctx.count_or(kDefaultSpecialRays);
  RaySet set;
  switch (spec.category) {
    case Category::ClosestHit: {
      set.queries = Queries::Closest;
      if (spec.origin) {
        // A viewpoint: rays from `origin` at interior points of the scene's triangles (deep_tree_rays' set), and
        // the kinds only when the check lists them. From far off every axis (all three coordinates large),
        // a test whose products take the vertices relative to the ray's origin (ray-space edge functions)
        // rounds them by u S^2 against the u S of a test that takes them relative to a vertex
        // (docs/grading.md, "The thirteenth round: a threaded BVH").
        if (!scene.geometry.has_triangles()) suite_error(ctx, "a closest-hit check with an origin needs triangles");
        set.rays = deep_tree_rays(scene, count, spec.seed, spec.origin);
      }
      std::vector<crosscheck::RayKind> kinds =
          spec.rays.empty() ? (spec.origin ? std::vector<crosscheck::RayKind>{} : std::vector{crosscheck::RayKind::Camera})
                            : spec.rays;
      if (spec.image) {
        // The image's pixels first; the other kinds follow.
        PixelRays pixels = camera_pixel_rays(scene, ctx.count_or(kDefaultKindRays));
        set.image_width = pixels.width;
        set.image_height = pixels.height;
        set.rays.insert(set.rays.begin(), pixels.rays.begin(), pixels.rays.end());
        std::erase(kinds, crosscheck::RayKind::Camera);
      }
      for (const crosscheck::RayKind k : kinds) {
        const std::vector<Ray> some =
            kind_rays(k, scene, ctx.scene.reference("embree"), ctx.count_or(kDefaultKindRays), spec.seed);
        set.rays.insert(set.rays.end(), some.begin(), some.end());
      }
      break;
    }
    case Category::AnyHit:
      set.queries = Queries::Any;
      set.rays = ctx.rays_of_kinds({crosscheck::RayKind::Shadow}, ctx.count_or(kDefaultKindRays));
      break;
    case Category::RayInterval: {
      // count is the number of variants; each base ray that hits gives four.
      const std::vector<Ray> rays = ctx.rays_of_kinds({crosscheck::RayKind::Camera, crosscheck::RayKind::Shadow},
                                                      std::max<std::size_t>(1, count / 4));
      const Answers first = trace_rays(ctx.scene.reference(ctx.reference_name()), rays, Queries::Closest);
      set.rays = interval_rays(rays, first.hits);
      set.ends = unambiguous_ends(ctx.scene.arbiter(),
                                  interval_end_rays(scene, std::max<std::size_t>(1, count / 4), spec.seed));
      break;
    }
    case Category::AxisAligned: set.rays = axis_aligned_rays(scene, count, spec.seed); break;
    case Category::Spheres:
      if (!scene.geometry.has_spheres()) suite_error(ctx, "a spheres check needs a scene with spheres");
      set.rays = sphere_rays(scene, count, spec.seed);
      break;
    case Category::Ties:
      if (!scene.geometry.has_triangles()) suite_error(ctx, "a ties check needs a scene with (duplicated) triangles");
      set.queries = Queries::Closest;
      set.rays = tie_rays(scene, count, spec.seed);
      break;
    case Category::DeepTree:
      if (!scene.geometry.has_triangles()) suite_error(ctx, "a deep-tree check needs a scene with triangles");
      set.rays = deep_tree_rays(scene, count, spec.seed, spec.origin);
      break;
    default: throw std::logic_error("not an answer check");
  }
  if (set.rays.empty()) suite_error(ctx, "its scene gives no rays of the requested kinds");
  return set;
}

}  // namespace

CheckVerdict run_answer_check(CheckContext& ctx) {
  const RaySet set = rays_for(ctx);
  const std::string reference = ctx.reference_name();
  // The ties check measures the tie rule itself; elsewhere a plugin is held to it only when it claims it.
  const bool tie_rule = ctx.spec.category == Category::Ties || ctx.env.plugin.traits().honours_ties;

  PluginInstance plugin = ctx.built_plugin();
  const Answers mine = trace_rays(*plugin, set.rays, set.queries);
  std::vector<Ray> end_rays;
  for (const IntervalEndRay& e : set.ends) end_rays.push_back(e.ray);
  const Answers mine_at_ends = end_rays.empty() ? Answers{} : trace_rays(*plugin, end_rays, Queries::Both);
  // The two-instances check: the second instance, built after the first, answers for its own scene too (a
  // plugin whose later instances keep the first one's tree fails here, not above).
  RaySet second_set;
  Answers second_mine;
  if (ctx.second_scene != nullptr) {
    CheckContext second{ctx.spec, *ctx.second_scene, ctx.env, ctx.deadline, nullptr};
    second_set = rays_for(second);
    plugin.use_instance(1);
    second_mine = trace_rays(*plugin, second_set.rays, second_set.queries);
    plugin.use_instance(0);
  }
  plugin.end();
  const EndJudgement ends = judge_ends(set.ends, mine_at_ends);
  const Answers expected = trace_rays(ctx.scene.reference(reference), set.rays, set.queries);
  const Judgement j = judge(ctx.scene, set.rays, mine, expected,
                            {set.queries, reference, tie_rule, "plugin", ctx.env.plugin.traits().watertight});

  std::optional<Judgement> second_j;
  if (ctx.second_scene != nullptr)
    second_j = judge(*ctx.second_scene, second_set.rays, second_mine,
                     trace_rays(ctx.second_scene->reference(reference), second_set.rays, second_set.queries),
                     {second_set.queries, reference, tie_rule, "plugin", ctx.env.plugin.traits().watertight});
  const std::size_t second_wrong = second_j ? second_j->wrong_total() : 0;

  const std::size_t answers = set.rays.size() * (set.queries == Queries::Both ? 2 : 1);
  CheckVerdict v;
  v.passed = j.wrong_total() == 0 && ends.wrong == 0 && second_wrong == 0;
  v.figures = judgement_figures(j, set.rays.size(), answers, j.wrong_total() + ends.wrong, reference);
  if (second_j) {
    v.figures["second_instance_rays"] = second_set.rays.size();
    v.figures["second_instance_wrong"] = second_wrong;
  }
  if (!set.ends.empty()) {
    v.figures["interval_end_rays"] = set.ends.size();
    v.figures["wrong_interval_ends"] = ends.wrong;
  }
  const std::string at_ends =
      set.ends.empty() ? "" : fmt::format(", and all {} answers at the exact ends of intervals", 2 * set.ends.size());
  const std::string second_words =
      second_j ? fmt::format(", and all {} of the second instance (scene '{}')", second_set.rays.size(), ctx.spec.second_scene)
               : "";
  if (v.passed) {
    v.detail = fmt::format("all {} answers right{}{}{}", answers, summary_of_allowed(j), at_ends, second_words);
  } else if (j.wrong_total() == 0 && ends.wrong == 0) {
    // Only the second instance answered wrong: the first was right after the second's build.
    const WrongAnswer& first = second_j->wrong.front();
    v.detail = fmt::format("the first instance's {} answers right, but {} of {} answers of a second instance built on "
                           "scene '{}' in the same process wrong; first, ray {}: {}",
                           answers, second_wrong, second_set.rays.size(), ctx.spec.second_scene, first.ray,
                           second_j->first_wrong_description);
    v.reproduce = ctx.grade_command();
    // Asked of one fresh instance built on the second scene alone (what `twinray trace` does): the same wrong
    // answer means the plugin is wrong on that scene itself, and the trace reproduces it; another answer means
    // the second instance answered under the first one's influence.
    const CheckContext second{ctx.spec, *ctx.second_scene, ctx.env, ctx.deadline, nullptr};
    const Ray& ray = second_set.rays[first.ray];
    const std::optional<CheckContext::AloneAnswer> alone = second.answer_alone(ray);
    const bool same = alone && (first.any_hit ? alone->occluded == (second_mine.occluded[first.ray] != 0)
                                              : same_bits(alone->hit, second_mine.hits[first.ray]));
    if (alone) v.figures["replays_alone"] = same;
    if (same) {
      v.detail += fmt::format(" (one instance built on scene '{}' alone answers the same: the plugin is wrong on that "
                              "scene itself)",
                              ctx.spec.second_scene);
      v.reproduce = second.trace_command(ray);
    } else {
      v.detail += " (instances must be independent: the second must answer for its own scene)";
    }
  } else if (j.wrong_total() == 0) {
    const IntervalEndRay& e = set.ends[*ends.first];
    v.detail = fmt::format("{} of {} answers at the exact ends of intervals wrong (closed: tmin <= t <= tmax); first, "
                           "interval-end ray {}: {}",
                           ends.wrong, 2 * set.ends.size(), *ends.first, ends.first_description);
    v.reproduce = ctx.trace_command(e.ray);
    ctx.confirm_replay(v, e.ray, ends.first_any_hit, ends.first_any_hit ? Hit{} : mine_at_ends.hits[*ends.first],
                       ends.first_any_hit && mine_at_ends.occluded[*ends.first] != 0);
  } else {
    const WrongAnswer& first = j.wrong.front();
    v.detail = fmt::format("{} of {} answers wrong ({:.3g}%); first, ray {}: {}", j.wrong_total(), answers,
                           100.0 * static_cast<double>(j.wrong_total()) / static_cast<double>(answers), first.ray,
                           j.first_wrong_description);
    v.reproduce = ctx.trace_command(set.rays[first.ray]);
    ctx.confirm_replay(v, set.rays[first.ray], first.any_hit, first.any_hit ? Hit{} : mine.hits[first.ray],
                       first.any_hit && mine.occluded[first.ray] != 0);
  }

  if (set.image_width > 0 && ctx.env.images) {
    const std::size_t pixels = static_cast<std::size_t>(set.image_width) * static_cast<std::size_t>(set.image_height);
    v.image = disagreement_image(set.image_width, set.image_height, std::span<const Ray>(set.rays.data(), pixels),
                                 std::span<const Hit>(expected.hits.data(), pixels), j.wrong);
  }
  return v;
}

}  // namespace twinray::grade
