// The roulette rule (core/render/russian_roulette.h): which paths are rouletted, with what probability,
// and that surviving paths are reweighted so the estimator stays unbiased.

#include "core/render/russian_roulette.h"

#include <gtest/gtest.h>

#include <limits>

namespace twinray {
namespace {

TEST(RussianRoulette, NoRouletteBeforeRrDepth) {
  EXPECT_EQ(roulette_survival(4, 5, glm::vec3(0.01f), 1.0f), 1.0f);
}

TEST(RussianRoulette, SurvivalIsScaledMaxThroughputTimesEtaSquaredBelowOne) {
  EXPECT_EQ(kSurvivalScale, 3.0f);
  EXPECT_FLOAT_EQ(roulette_survival(5, 5, glm::vec3(0.1f, 0.2f, 0.05f), 1.0f), 0.6f);
  // Inside ior-1.5 glass the throughput carries 1/1.5^2 and eta_scale 1.5^2: not killed for it.
  EXPECT_FLOAT_EQ(roulette_survival(9, 5, glm::vec3(0.1f / 2.25f), 2.25f), 0.3f);
}

TEST(RussianRoulette, PathsWithScaledThroughputOneOrMoreAreNotRouletted) {
  EXPECT_EQ(roulette_survival(6, 5, glm::vec3(1.0f), 1.0f), 1.0f);
  EXPECT_EQ(roulette_survival(6, 5, glm::vec3(0.0f, 1.0f / 3.0f, 0.0f), 1.0f), 1.0f);
  EXPECT_LT(roulette_survival(6, 5, glm::vec3(0.0f, 0.33f, 0.0f), 1.0f), 1.0f);
  EXPECT_EQ(roulette_survival(kForcedRouletteDepth - 1, 5, glm::vec3(3.0f, 0.0f, 0.0f), 1.0f), 1.0f);
}

TEST(RussianRoulette, EveryPathIsRoulettedFromTheForcedDepthOn) {
  EXPECT_EQ(roulette_survival(kForcedRouletteDepth, 5, glm::vec3(1.0f), 1.0f), kMaxSurvival);
  EXPECT_LT(kMaxSurvival, 1.0f);
  EXPECT_FLOAT_EQ(roulette_survival(kForcedRouletteDepth, 5, glm::vec3(0.25f), 1.0f), 0.75f);
  EXPECT_FLOAT_EQ(roulette_survival(kForcedRouletteDepth, 5, glm::vec3(0.25f), 1.0f / 3.0f), 0.25f);
}

TEST(RussianRoulette, SurvivorsAreReweightedAndNoRandomNumberIsDrawnWithoutRoulette) {
  Rng rng(3, 0), copy(3, 0);
  glm::vec3 t(1.0f);
  EXPECT_TRUE(survive_roulette(6, 5, 1.0f, t, rng));
  EXPECT_EQ(t, glm::vec3(1.0f));
  EXPECT_EQ(rng.next_float(), copy.next_float());  // the stream did not advance

  // Unbiased: the mean of the reweighted throughput over many trials is the throughput itself.
  constexpr int kTrials = 200000;
  double sum = 0.0;
  for (int i = 0; i < kTrials; ++i) {
    glm::vec3 p(0.1f, 0.05f, 0.02f);
    if (survive_roulette(8, 5, 1.0f, p, rng)) sum += p.x;
  }
  // Survival q = 0.3 with weight 0.1 / 0.3: standard error (1/3) sqrt(0.3 * 0.7 / n) ~ 3.4e-4; 5 standard errors.
  EXPECT_NEAR(sum / kTrials, 0.1, 1.75e-3);
}

TEST(RussianRoulette, NanThroughputEndsThePath) {
  Rng rng(1, 0);
  glm::vec3 t(std::numeric_limits<float>::quiet_NaN());
  EXPECT_FALSE(survive_roulette(kForcedRouletteDepth, 5, 1.0f, t, rng));
}

}  // namespace
}  // namespace twinray
