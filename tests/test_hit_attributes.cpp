// The attribute rule of harness/crosscheck/hit_attributes.h: every built-in backend's u, v and ng pass it on
// the grading scenes (so it can never fail a correct intersector), and the classic attribute bugs (swapped
// barycentrics, a flipped or missing normal, NaN, a sphere's u left in (-0.5, 0.5]) fail it.

#include "backends/registry.h"
#include "harness/crosscheck/hit_attributes.h"
#include "harness/grade/answers.h"
#include "harness/grade/grade_rays.h"
#include "harness/grade/grade_scene.h"
#include "harness/grade/suite.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace twinray::crosscheck {
namespace {

grade::Suite attribute_suite() {
  grade::Suite s;
  s.name = "attributes-test";
  s.dir = std::filesystem::temp_directory_path();
  return s;
}

// Rays of several kinds over one scene, and the hits of `backend` for them.
struct Traced {
  std::vector<Ray> rays;
  std::vector<Hit> hits;
};

Traced trace(grade::GradeScene& scene, const Backend& backend) {
  Traced t;
  const Backend& source = scene.reference("embree");
  for (const RayKind kind : {RayKind::Camera, RayKind::Uniform, RayKind::Diffuse}) {
    const std::vector<Ray> some = grade::kind_rays(kind, scene.scene(), source, 1500, 5);
    t.rays.insert(t.rays.end(), some.begin(), some.end());
  }
  if (scene.geometry().has_spheres()) {
    const std::vector<Ray> some = grade::sphere_rays(scene.scene(), 1500, 5);
    t.rays.insert(t.rays.end(), some.begin(), some.end());
  }
  t.hits.resize(t.rays.size());
  backend.intersect(t.rays, std::span<Hit>(t.hits));
  return t;
}

class HitAttributes : public ::testing::TestWithParam<std::string> {};

// No false failure: the rule holds every built-in backend (float and exact, watertight and not) on triangles
// far from and near the origin, slivers of a soup, axis-aligned faces and spheres from 1e-3 to 1e4.
TEST_P(HitAttributes, EveryBuiltInBackendFollowsTheConventions) {
  for (const std::string scene_name : {"procedural:soup:3000:7", "procedural:mixed:50:2000:5", "procedural:sphere-sizes",
                                       "procedural:box:-2:2", "procedural:sphere-mesh:4:10000:-20000:5000:3"}) {
    grade::GradeScene scene(grade::SuiteScene{"s", scene_name, false}, attribute_suite());
    const std::unique_ptr<Backend> backend = make_backend(GetParam());
    backend->build(scene.geometry());
    const Traced t = trace(scene, *backend);
    std::size_t hits = 0;
    for (std::size_t i = 0; i < t.rays.size(); ++i) {
      if (!t.hits[i].found()) continue;
      ++hits;
      const AttributeRuling r = rule_attributes(scene.index(), t.rays[i], t.hits[i]);
      ASSERT_TRUE(r.right) << GetParam() << " on " << scene_name << ", ray " << i << ": " << r.detail;
    }
    EXPECT_GT(hits, 300u) << scene_name;
  }
}

INSTANTIATE_TEST_SUITE_P(Backends, HitAttributes,
                         ::testing::Values("bvh", "bvh8", "embree", "embree-fast", "brute", "exact"),
                         [](const ::testing::TestParamInfo<std::string>& p) {
                           std::string name = p.param;
                           for (char& c : name)
                             if (c == '-') c = '_';
                           return name;
                         });

// The bugs, planted into brute's right answers.
class HitAttributeBugs : public ::testing::Test {
 protected:
  HitAttributeBugs() : scene_(grade::SuiteScene{"s", "procedural:mixed:50:2000:5", false}, attribute_suite()) {
    const Traced all = trace(scene_, scene_.reference("brute"));
    // Without the sphere rays from thousands of radii away: the rule's tolerance grows with the largest
    // coordinate of the ray origin (a float test's barycentrics are that far off), and there a planted swap on
    // a small triangle can stay within it. Every other ray starts within a few scene diagonals.
    const Bounds3 box = scene_.scene().geometry.bounds();
    for (std::size_t i = 0; i < all.rays.size(); ++i) {
      if (glm::length(all.rays[i].org - box.center()) > 5.0f * box.diagonal()) continue;
      traced_.rays.push_back(all.rays[i]);
      traced_.hits.push_back(all.hits[i]);
    }
  }

  // How many of the hits on triangles (or on spheres) `plant` makes wrong, and how many it touched.
  template <typename Plant>
  std::pair<std::size_t, std::size_t> wrong_after(bool spheres, Plant plant) {
    std::size_t touched = 0, wrong = 0;
    for (std::size_t i = 0; i < traced_.rays.size(); ++i) {
      Hit h = traced_.hits[i];
      if (!h.found() || (scene_.index().sphere(h.geom_id) != nullptr) != spheres) continue;
      if (!plant(h)) continue;
      ++touched;
      wrong += rule_attributes(scene_.index(), traced_.rays[i], h).right ? 0 : 1;
    }
    return {wrong, touched};
  }

  grade::GradeScene scene_;
  Traced traced_;
};

TEST_F(HitAttributeBugs, SwappedBarycentricsAreWrongWhereverUAndVDiffer) {
  const auto [wrong, touched] = wrong_after(false, [](Hit& h) {
    if (std::fabs(h.u - h.v) < 0.05f) return false;  // near u = v the swap moves the point by little
    std::swap(h.u, h.v);
    return true;
  });
  EXPECT_GT(touched, 500u);
  EXPECT_EQ(wrong, touched);
}

TEST_F(HitAttributeBugs, FlippedUnnormalisedOrNanNormalsAreWrong) {
  for (const auto& plant : std::vector<std::function<void(Hit&)>>{[](Hit& h) { h.ng = -h.ng; },
                                                                   [](Hit& h) { h.ng *= 2.0f; },
                                                                   [](Hit& h) { h.ng = glm::vec3(0.0f); },
                                                                   [](Hit& h) { h.ng.x = NAN; }}) {
    for (const bool spheres : {false, true}) {
      const auto [wrong, touched] = wrong_after(spheres, [&](Hit& h) {
        plant(h);
        return true;
      });
      EXPECT_GT(touched, 100u);
      EXPECT_EQ(wrong, touched) << (spheres ? "spheres" : "triangles");
    }
  }
}

TEST_F(HitAttributeBugs, SphereUOutsideZeroToOneOrNamingAnotherDirectionIsWrong) {
  // atan2 / (2 pi) without adding 1 to negative angles: u in (-0.5, 0.5].
  const auto [wrong_range, negative] = wrong_after(true, [](Hit& h) {
    if (h.u <= 0.5f || h.u >= 0.99f) return false;
    h.u -= 1.0f;
    return true;
  });
  EXPECT_GT(negative, 50u);
  EXPECT_EQ(wrong_range, negative);
  // u and v swapped on a sphere name another direction.
  const auto [wrong_swap, swapped] = wrong_after(true, [](Hit& h) {
    if (std::fabs(h.u - h.v) < 0.05f || std::sin(3.14159265f * h.v) < 0.1f) return false;
    std::swap(h.u, h.v);
    return true;
  });
  EXPECT_GT(swapped, 50u);
  EXPECT_EQ(wrong_swap, swapped);
}

// In the grader's judge, a wrong attribute makes the closest-hit answer wrong even though t and the primitive
// are identical to the reference's, and the figures say why.
TEST_F(HitAttributeBugs, TheJudgeCountsThemAsWrongClosestHits) {
  grade::Answers reference{traced_.hits, {}, {}};
  grade::Answers plugin = reference;
  std::size_t planted = 0;
  for (Hit& h : plugin.hits)
    if (h.found() && scene_.index().mesh(h.geom_id) != nullptr && std::fabs(h.u - h.v) > 0.05f) {
      std::swap(h.u, h.v);
      ++planted;
    }
  const grade::Judgement j =
      grade::judge(scene_, traced_.rays, plugin, reference, {grade::Queries::Closest, "brute", false, "plugin", false});
  EXPECT_EQ(j.wrong_closest, planted);
  EXPECT_EQ(j.wrong_attributes, planted);
  EXPECT_NE(j.first_wrong_description.find("wrong attributes: u"), std::string::npos) << j.first_wrong_description;
}

}  // namespace
}  // namespace twinray::crosscheck
