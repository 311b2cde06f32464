// Judging in `twinray grade` (harness/grade/answers.h): every disagreement with the reference is ruled by
// the arbiter, so a plugin is right where the reference erred and wrong where it erred itself.

#include "backends/registry.h"
#include "core/sampling/rng.h"
#include "harness/grade/answers.h"
#include "harness/grade/grade_scene.h"
#include "harness/grade/suite.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

namespace twinray::grade {
namespace {

class GradeJudge : public ::testing::Test {
 protected:
  GradeJudge() : scene_(SuiteScene{"box", "procedural:box:-2:2", false}, suite()) {
    // Rays from a shell around the box toward points inside it: every one crosses two faces.
    Rng rng(21, 3);
    for (int i = 0; i < 400; ++i) {
      const glm::vec3 org(8.0f * rng.next_float() - 4.0f, 8.0f * rng.next_float() - 4.0f, 6.0f + rng.next_float());
      const glm::vec3 target(2.0f * rng.next_float() - 1.0f, 2.0f * rng.next_float() - 1.0f, 2.0f * rng.next_float() - 1.0f);
      rays_.push_back(Ray{org, 0.0f, target - org, 1e30f});
    }
    truth_ = trace_rays(scene_.reference("brute"), rays_, Queries::Both);
  }

  static Suite suite() {
    Suite s;
    s.name = "judge-test";
    s.dir = std::filesystem::temp_directory_path();
    return s;
  }

  // `answers` with every tenth hit moved 1% farther (the same primitive, a t no correct intersector gives).
  static Answers with_wrong_t(Answers answers, std::size_t& planted) {
    planted = 0;
    for (std::size_t i = 0; i < answers.hits.size(); i += 10) {
      if (!answers.hits[i].found()) continue;
      answers.hits[i].t *= 1.01f;
      ++planted;
    }
    return answers;
  }

  JudgeOptions options() const { return {Queries::Both, "embree", false, "plugin", false}; }

  GradeScene scene_;
  std::vector<Ray> rays_;
  Answers truth_;
};

TEST_F(GradeJudge, AnswersEqualToTheReferenceAreNotRuled) {
  const Judgement j = judge(scene_, rays_, truth_, truth_, options());
  EXPECT_EQ(j.wrong_total(), 0u);
  EXPECT_EQ(j.ruled, 0u);
}

TEST_F(GradeJudge, ThePluginIsRightWhereTheReferenceErred) {
  std::size_t planted = 0;
  const Answers erring_reference = with_wrong_t(truth_, planted);
  ASSERT_GT(planted, 20u);
  const Judgement j = judge(scene_, rays_, truth_, erring_reference, options());
  EXPECT_EQ(j.wrong_total(), 0u);
  EXPECT_EQ(j.ruled, planted);
  EXPECT_EQ(j.overruled, planted);
  EXPECT_EQ(j.second_opinion, "exact");
}

TEST_F(GradeJudge, ThePluginIsWrongWhereItErredAndTheRulingSaysWhy) {
  std::size_t planted = 0;
  const Answers erring_plugin = with_wrong_t(truth_, planted);
  const Judgement j = judge(scene_, rays_, erring_plugin, truth_, options());
  EXPECT_EQ(j.wrong_closest, planted);
  EXPECT_EQ(j.wrong_any, 0u);
  EXPECT_EQ(j.overruled, 0u);
  ASSERT_FALSE(j.wrong.empty());
  EXPECT_EQ(j.wrong.front().ray, 0u);
  EXPECT_NE(j.first_wrong_description.find("exact arithmetic"), std::string::npos) << j.first_wrong_description;
  EXPECT_NE(j.first_wrong_description.find("t-off"), std::string::npos) << j.first_wrong_description;
}

TEST_F(GradeJudge, AnyHitAnswersAreRuledToo) {
  Answers plugin = truth_;
  Answers reference = truth_;
  // The plugin denies occlusion on rays that certainly cross the box; the reference claims it on rays cut
  // short before the box (where the plugin, saying "not occluded", is right).
  std::vector<Ray> rays = rays_;
  std::size_t denied = 0, claimed = 0;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    if (!truth_.hits[i].found()) continue;
    if (i % 7 == 0) {
      plugin.occluded[i] = 0;
      ++denied;
    } else if (i % 7 == 1) {
      rays[i].tmax = 0.5f * truth_.hits[i].t;
      plugin.occluded[i] = 0;
      reference.occluded[i] = 1;
      ++claimed;
    }
  }
  ASSERT_GT(denied, 10u);
  ASSERT_GT(claimed, 10u);
  JudgeOptions o = options();
  o.queries = Queries::Any;
  const Judgement j = judge(scene_, rays, plugin, reference, o);
  EXPECT_EQ(j.wrong_any, denied);
  EXPECT_EQ(j.overruled, claimed);
}

}  // namespace
}  // namespace twinray::grade
