// The grading ray sets (harness/grade/grade_rays.h): each has the property its check relies on.

#include "backends/registry.h"
#include "core/camera/pinhole_camera.h"
#include "harness/grade/grade_rays.h"
#include "harness/grade/interval_ends.h"
#include "harness/scenes/named_scene.h"
#include "tests/cli_runner.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

namespace twinray::grade {
namespace {

bool has_zero_component(const glm::vec3& d) { return d.x == 0.0f || d.y == 0.0f || d.z == 0.0f; }

TEST(GradeRays, AxisAlignedRaysHaveExactZerosOfBothSignsAndOriginsOnFaces) {
  const Scene scene = load_named_scene("procedural:box:-2:2");
  const Bounds3 b = scene.geometry.bounds();
  const std::vector<Ray> rays = axis_aligned_rays(scene, 400, 5);
  ASSERT_EQ(rays.size(), 400u);
  std::size_t negative_zero = 0, positive_zero = 0, on_face = 0;
  for (const Ray& r : rays) {
    ASSERT_TRUE(is_valid_ray(r));
    EXPECT_TRUE(has_zero_component(r.dir));
    for (int a = 0; a < 3; ++a) {
      if (r.dir[a] == 0.0f) (std::signbit(r.dir[a]) ? negative_zero : positive_zero) += 1;
      if (r.org[a] == b.lo[a] || r.org[a] == b.hi[a]) ++on_face;
    }
  }
  EXPECT_GT(negative_zero, 50u);
  EXPECT_GT(positive_zero, 50u);
  EXPECT_GE(on_face, 200u);  // half of them start exactly on a face
}

TEST(GradeRays, IntervalVariantsStraddleTheFirstHit) {
  const Ray r = {glm::vec3(0.0f, 0.0f, 5.0f), 0.0f, glm::vec3(0.0f, 0.0f, -1.0f), INFINITY};
  Hit h;
  h.t = 5.0f;
  h.geom_id = h.prim_id = 0;
  const std::vector<Ray> v = interval_rays(std::span<const Ray>(&r, 1), std::span<const Hit>(&h, 1));
  ASSERT_EQ(v.size(), 4u);
  EXPECT_LT(v[0].tmax, 5.0f);  // ends before
  EXPECT_GT(v[1].tmin, 5.0f);  // starts after
  EXPECT_GT(v[2].tmax, 5.0f);  // ends after
  EXPECT_LT(v[3].tmin, 5.0f);  // starts before
  for (const Ray& x : v) EXPECT_TRUE(is_valid_ray(x));
  Hit miss;
  EXPECT_TRUE(interval_rays(std::span<const Ray>(&r, 1), std::span<const Hit>(&miss, 1)).empty());
}

TEST(GradeRays, WatertightRaysAllHitAClosedMesh) {
  const Scene scene = load_named_scene("procedural:sphere-mesh:3");
  const auto embree = make_backend("embree");
  embree->build(scene.geometry);
  const std::vector<Ray> rays = watertight_rays(scene, 2000, 1, std::nullopt);
  ASSERT_EQ(rays.size(), 2000u);
  std::size_t misses = 0;
  for (const Ray& r : rays) {
    Hit h;
    misses += embree->intersect(r, h) ? 0 : 1;
  }
  EXPECT_EQ(misses, 0u);  // robust Embree is watertight: every ray of the set must hit
}

TEST(GradeRays, SphereRaysHitAndMissAsDesigned) {
  const Scene scene = load_named_scene("procedural:sphere-sizes");
  const auto brute = make_backend("brute");
  brute->build(scene.geometry);
  const std::vector<Ray> rays = sphere_rays(scene, 600, 1);
  std::size_t hits = 0;
  for (const Ray& r : rays) {
    Hit h;
    hits += brute->intersect(r, h) ? 1 : 0;
  }
  // Every kind is present: neither all hits nor all misses.
  EXPECT_GT(hits, 200u);
  EXPECT_LT(hits, 650u);  // of 712: 600, 75 segments, 37 past their sphere
  // The rays whose tmin lies inside the sphere (between its roots) all hit, beyond tmin: the far root.
  std::size_t inside_interval = 0;
  for (const Ray& r : rays) {
    if (r.tmin != 1.0f) continue;
    ++inside_interval;
    Hit h;
    ASSERT_TRUE(brute->intersect(r, h));
    EXPECT_GT(h.t, r.tmin);
    Ray from_zero = r;
    from_zero.tmin = 0.0f;
    Hit near;
    ASSERT_TRUE(brute->intersect(from_zero, near));
    EXPECT_LT(near.t, r.tmin);  // the near root (at least) is before tmin
  }
  EXPECT_GE(inside_interval, 600u / 8);
  // The segments inside a ball (finite tmax) cross no surface: a miss, and not occluded (in this scene no other
  // sphere reaches into a ball). A test that treats the sphere as solid answers them wrong.
  std::size_t segments = 0;
  for (const Ray& r : rays) {
    if (std::isinf(r.tmax)) continue;
    ++segments;
    Hit h;
    EXPECT_FALSE(brute->intersect(r, h));
    EXPECT_FALSE(brute->occluded(r));
  }
  EXPECT_EQ(segments, 600u / 8);
  // The rays that start past their sphere (tmin 2.5): from 0 they hit it before t 1.91; from tmin they do not
  // hit that sphere again (a miss, or another sphere beyond).
  std::size_t past = 0;
  for (const Ray& r : rays) {
    if (r.tmin != 2.5f) continue;
    ++past;
    Ray from_zero = r;
    from_zero.tmin = 0.0f;
    Hit aimed;
    ASSERT_TRUE(brute->intersect(from_zero, aimed));
    EXPECT_LT(aimed.t, 1.91f);
    Hit h;
    if (brute->intersect(r, h)) {
      EXPECT_NE(h.geom_id, aimed.geom_id);
      EXPECT_GE(h.t, r.tmin);
    }
  }
  EXPECT_EQ(past, 600u / 16);
}

// Rays whose interval ends exactly at a crossing (interval_ends.h): on the Cornell box's walls and the integer
// box, most survive the exact filter, all four kinds of interval occur, and every built-in backend answers
// every one as the closed interval says: the crossing counts at t == tmin and at t == tmax, and not one float
// beyond (embree-fast but at tmin, below). A scene without such triangles (a soup) gives none.
TEST(GradeRays, IntervalEndRaysAreAnsweredExactlyByEveryBackend) {
  EXPECT_TRUE(interval_end_rays(load_named_scene("procedural:soup:500:1"), 100, 1).empty());
  for (const char* name : {"scenes/cornell-box.json", "procedural:box:-2:2"}) {
    const Scene scene = load_named_scene(name, testing::source_path(""));
    const std::vector<IntervalEndRay> all = interval_end_rays(scene, 400, 3);
    ASSERT_EQ(all.size(), 400u) << name;
    const arbiter::Arbiter exact(scene.geometry);
    const std::vector<IntervalEndRay> ends = unambiguous_ends(exact, all);
    EXPECT_GT(ends.size(), 200u) << name;
    std::size_t at_tmin = 0, at_tmax = 0, outside = 0;
    std::vector<Ray> rays;
    for (const IntervalEndRay& e : ends) {
      ASSERT_TRUE(is_valid_ray(e.ray));
      rays.push_back(e.ray);
      if (!e.counts) ++outside;
      else (e.ray.tmin == e.t ? at_tmin : at_tmax) += 1;
    }
    EXPECT_GT(at_tmin, 30u) << name;
    EXPECT_GT(at_tmax, 30u) << name;
    EXPECT_GT(outside, 60u) << name;
    for (const char* backend : {"embree", "bvh", "bvh8", "brute"}) {
      const auto b = make_backend(backend);
      b->build(scene.geometry);
      const Answers answers = trace_rays(*b, rays, Queries::Both);
      const EndJudgement j = judge_ends(ends, answers);
      EXPECT_EQ(j.wrong, 0u) << backend << " on " << name << ": " << j.first_description;
    }
    // Embree's fast (non-robust) triangle kernel takes tnear as open, (tnear, tfar]: embree-fast loses some of
    // the crossings exactly at tmin, and answers every other ray right (docs/grading.md, "Interval ends").
    const auto fast = make_backend("embree-fast");
    fast->build(scene.geometry);
    const Answers fast_answers = trace_rays(*fast, rays, Queries::Both);
    std::vector<IntervalEndRay> not_at_tmin;
    Answers fast_not_at_tmin;
    for (std::size_t i = 0; i < ends.size(); ++i)
      if (!(ends[i].counts && ends[i].ray.tmin == ends[i].t)) {
        not_at_tmin.push_back(ends[i]);
        fast_not_at_tmin.hits.push_back(fast_answers.hits[i]);
        fast_not_at_tmin.occluded.push_back(fast_answers.occluded[i]);
      }
    EXPECT_EQ(judge_ends(not_at_tmin, fast_not_at_tmin).wrong, 0u) << name;
    const std::size_t fast_wrong = judge_ends(ends, fast_answers).wrong;
    EXPECT_GT(fast_wrong, 0u) << name;
    EXPECT_LE(fast_wrong, 2 * at_tmin) << name;
    // A closed interval taken as open, (tmin, tmax), loses exactly the crossings at the ends.
    const auto brute = make_backend("brute");
    brute->build(scene.geometry);
    Answers open = trace_rays(*brute, rays, Queries::Both);
    for (std::size_t i = 0; i < ends.size(); ++i)
      if (ends[i].counts) {
        open.hits[i] = Hit{};
        open.occluded[i] = 0;
      }
    EXPECT_EQ(judge_ends(ends, open).wrong, 2 * (at_tmin + at_tmax)) << name;
  }
}

TEST(GradeRays, RaySetsAreDeterministic) {
  const Scene scene = load_named_scene("procedural:soup:200:1");
  const auto same = [](const std::vector<Ray>& a, const std::vector<Ray>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(Ray)) == 0;
  };
  EXPECT_TRUE(same(axis_aligned_rays(scene, 100, 3), axis_aligned_rays(scene, 100, 3)));
  EXPECT_TRUE(same(tie_rays(scene, 100, 3), tie_rays(scene, 100, 3)));
  EXPECT_FALSE(same(tie_rays(scene, 100, 3), tie_rays(scene, 100, 4)));
}

TEST(GradeRays, PixelRaysCoverTheImageRowByRow) {
  const Scene scene = load_named_scene("procedural:grid:4:4");
  const PixelRays p = camera_pixel_rays(scene, 1000);
  EXPECT_EQ(p.rays.size(), static_cast<std::size_t>(p.width) * static_cast<std::size_t>(p.height));
  EXPECT_NEAR(static_cast<double>(p.rays.size()), 1000.0, 70.0);
  // Ray i is pixel (i % width, i / width): the first row sweeps left to right, the rows go top to bottom.
  const PinholeCamera camera(scene.camera);
  const auto w = static_cast<std::size_t>(p.width);
  for (std::size_t i = 1; i < w; ++i) EXPECT_GT(glm::dot(p.rays[i].dir, camera.right()), glm::dot(p.rays[i - 1].dir, camera.right()));
  EXPECT_GT(glm::dot(p.rays[0].dir, camera.up()), glm::dot(p.rays[p.rays.size() - w].dir, camera.up()));
}

}  // namespace
}  // namespace twinray::grade
