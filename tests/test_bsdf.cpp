// The BSDFs: sampled directions follow the densities they report, energy is conserved, Fresnel and Snell
// hold exactly, and the MIS weights of the two strategies sum to one.

#include "core/materials/bsdf.h"
#include "core/materials/fresnel.h"
#include "core/render/light_transport.h"
#include "core/sampling/rng.h"
#include "core/sampling/warp.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

namespace twinray {
namespace {

Material make(MaterialType type) {
  Material m;
  m.type = type;
  m.albedo = glm::vec3(0.8f, 0.5f, 0.2f);
  m.reflectance = glm::vec3(0.9f, 0.7f, 0.3f);
  m.ior = 1.5f;
  return m;
}

// Chi-square test of Lambertian sampling: directions binned by (cos theta, phi) around the normal on the
// side of wo, against the exact probability of each bin under the reported density cos/pi.
TEST(Bsdf, LambertianSamplesFollowTheCosineDensity) {
  const Bsdf bsdf = Bsdf::from_material(make(MaterialType::Diffuse));
  const glm::vec3 ng = glm::normalize(glm::vec3(0.3f, 1.0f, -0.2f));
  constexpr int kCosBins = 10, kPhiBins = 8, kSamples = 200000;
  for (float side : {1.0f, -1.0f}) {
    const glm::vec3 n = side * ng;
    const Frame frame = Frame::from_normal(n);
    const glm::vec3 wo = glm::normalize(frame.to_world(glm::vec3(0.4f, -0.3f, 0.8f)));
    std::vector<double> counts(kCosBins * kPhiBins, 0.0);
    Rng rng(11, 2);
    for (int i = 0; i < kSamples; ++i) {
      const auto s = bsdf.sample(wo, ng, rng.next_float(), {rng.next_float(), rng.next_float()});
      ASSERT_TRUE(s.has_value());
      ASSERT_FALSE(s->delta);
      const glm::vec3 local = frame.to_local(s->wi);
      ASSERT_GT(local.z, 0.0f) << "sampled below the surface";
      EXPECT_NEAR(s->pdf, bsdf.pdf(wo, s->wi, ng), 1e-6f);
      // weight = f cos / pdf, evaluated independently
      const glm::vec3 expect_weight = bsdf.eval(wo, s->wi, ng) / s->pdf;
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(s->weight[c], expect_weight[c], 1e-4f);
      const int ci = std::min(kCosBins - 1, static_cast<int>(local.z * kCosBins));
      float phi = std::atan2(local.y, local.x);
      if (phi < 0.0f) phi += 2.0f * kPi;
      const int pi = std::min(kPhiBins - 1, static_cast<int>(phi / (2.0f * kPi) * kPhiBins));
      counts[static_cast<std::size_t>(ci * kPhiBins + pi)] += 1.0;
    }
    double chi2 = 0.0;
    for (int ci = 0; ci < kCosBins; ++ci) {
      const double c0 = static_cast<double>(ci) / kCosBins, c1 = static_cast<double>(ci + 1) / kCosBins;
      // integral of cos/pi over the bin = (dphi / pi) (c1^2 - c0^2) / 2
      const double p = (2.0 * std::numbers::pi / kPhiBins / std::numbers::pi) * 0.5 * (c1 * c1 - c0 * c0);
      for (int pi = 0; pi < kPhiBins; ++pi) {
        const double expected = p * kSamples;
        const double d = counts[static_cast<std::size_t>(ci * kPhiBins + pi)] - expected;
        chi2 += d * d / expected;
      }
    }
    // 79 degrees of freedom: mean 79, sd 12.6. 79 + 6 sd has a false-alarm probability below 1e-6.
    const double dof = kCosBins * kPhiBins - 1;
    EXPECT_LT(chi2, dof + 6.0 * std::sqrt(2.0 * dof)) << "side " << side;
  }
}

TEST(Bsdf, LambertianIsTwoSidedAndIntegratesToItsAlbedo) {
  const Bsdf bsdf = Bsdf::from_material(make(MaterialType::Diffuse));
  const glm::vec3 ng(0, 1, 0);
  const glm::vec3 wo = glm::normalize(glm::vec3(0.2f, -1.0f, 0.1f));  // below: the back side
  // Integral over the sphere of eval (= f |cos|) by uniform sphere sampling: albedo.
  Rng rng(5, 1);
  constexpr int n = 400000;
  glm::dvec3 sum(0.0);
  for (int i = 0; i < n; ++i) {
    const glm::vec3 wi = sample_uniform_sphere({rng.next_float(), rng.next_float()});
    sum += glm::dvec3(bsdf.eval(wo, wi, ng)) / static_cast<double>(uniform_sphere_pdf());
    if (wi.y > 0.0f) {
      ASSERT_EQ(bsdf.eval(wo, wi, ng), glm::vec3(0.0f)) << "light leaked through the surface";
    }
  }
  const glm::dvec3 mean = sum / static_cast<double>(n);
  // Standard error of the estimator: f|cos|/p has variance < (albedo * 4 * 1)^2 * 1/2 ; 4 sigma ~ 0.02 * albedo
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(mean[c], make(MaterialType::Diffuse).albedo[c], 0.01);
}

TEST(Bsdf, MirrorReflectsExactlyAndCarriesItsReflectance) {
  const Material m = make(MaterialType::Mirror);
  const Bsdf bsdf = Bsdf::from_material(m);
  const glm::vec3 ng = glm::normalize(glm::vec3(0.1f, 1.0f, 0.3f));
  for (float theta : {0.0f, 0.5f, 1.2f, 1.55f}) {
    for (float side : {1.0f, -1.0f}) {
      const Frame f = Frame::from_normal(side * ng);
      const glm::vec3 wo = f.to_world({std::sin(theta), 0.0f, std::cos(theta)});
      const auto s = bsdf.sample(wo, ng, 0.3f, {0.1f, 0.9f});
      ASSERT_TRUE(s.has_value());
      EXPECT_TRUE(s->delta);
      EXPECT_NEAR(glm::dot(s->wi, ng), glm::dot(wo, ng), 1e-6f);
      EXPECT_NEAR(glm::length(glm::cross(s->wi + wo, ng)), 0.0f, 1e-5f) << "wi + wo must be along the normal";
      EXPECT_EQ(s->weight, m.reflectance);
      EXPECT_EQ(bsdf.eval(wo, s->wi, ng), glm::vec3(0.0f));
      EXPECT_EQ(bsdf.pdf(wo, s->wi, ng), 0.0f);
    }
  }
}

// Independent double-precision Fresnel for unpolarised light.
double fresnel_reference(double cos_i, double n1, double n2) {
  const double sin_t = n1 / n2 * std::sqrt(1.0 - cos_i * cos_i);
  if (sin_t >= 1.0) return 1.0;
  const double cos_t = std::sqrt(1.0 - sin_t * sin_t);
  const double rs = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t);
  const double rp = (n1 * cos_t - n2 * cos_i) / (n1 * cos_t + n2 * cos_i);
  return 0.5 * (rs * rs + rp * rp);
}

TEST(Fresnel, MatchesClosedFormsBothWays) {
  EXPECT_NEAR(fresnel_dielectric(1.0f, 1.5f).reflectance, 0.04f, 1e-6f);  // ((n-1)/(n+1))^2
  EXPECT_NEAR(fresnel_dielectric(-1.0f, 1.5f).reflectance, 0.04f, 1e-6f);
  EXPECT_EQ(fresnel_dielectric(0.3f, 1.0f).reflectance, 0.0f);
  // Brewster's angle: the p component vanishes.
  const double brewster = std::atan(1.5);
  const double cos_b = std::cos(brewster), cos_t = std::cos(std::numbers::pi / 2 - brewster);
  const double rs = (cos_b - 1.5 * cos_t) / (cos_b + 1.5 * cos_t);
  EXPECT_NEAR(fresnel_dielectric(static_cast<float>(cos_b), 1.5f).reflectance, 0.5 * rs * rs, 1e-6);
  for (double c = 0.02; c <= 1.0; c += 0.07) {
    EXPECT_NEAR(fresnel_dielectric(static_cast<float>(c), 1.5f).reflectance, fresnel_reference(c, 1.0, 1.5), 2e-6);
    EXPECT_NEAR(fresnel_dielectric(static_cast<float>(-c), 1.5f).reflectance, fresnel_reference(c, 1.5, 1.0), 2e-6);
  }
  // Beyond the critical angle from inside: total internal reflection.
  const float critical_cos = std::sqrt(1.0f - 1.0f / (1.5f * 1.5f));
  EXPECT_EQ(fresnel_dielectric(-(critical_cos - 0.01f), 1.5f).reflectance, 1.0f);
}

TEST(Bsdf, DielectricChoosesReflectionWithProbabilityFresnelAndRefractsBySnell) {
  const Material m = make(MaterialType::Glass);
  const Bsdf bsdf = Bsdf::from_material(m);
  const glm::vec3 ng = glm::normalize(glm::vec3(-0.2f, 1.0f, 0.1f));
  const Frame frame = Frame::from_normal(ng);
  for (float cos_o : {0.95f, 0.6f, 0.2f, -0.95f, -0.8f, -0.6f}) {
    const float sin_o = std::sqrt(1.0f - cos_o * cos_o);
    const glm::vec3 wo = frame.to_world({sin_o, 0.0f, cos_o});
    const double F = fresnel_reference(std::abs(cos_o), cos_o > 0 ? 1.0 : 1.5, cos_o > 0 ? 1.5 : 1.0);
    Rng rng(3, 9);
    constexpr int n = 20000;
    int reflected = 0;
    for (int i = 0; i < n; ++i) {
      const auto s = bsdf.sample(wo, ng, rng.next_float(), {rng.next_float(), rng.next_float()});
      ASSERT_TRUE(s.has_value());
      ASSERT_TRUE(s->delta);
      const float cos_i = glm::dot(s->wi, ng);
      if (cos_i * cos_o > 0.0f) {
        ++reflected;
        EXPECT_NEAR(cos_i, cos_o, 1e-5f);
        EXPECT_EQ(s->weight, glm::vec3(1.0f));
      } else {
        // Snell: eta_o sin_o = eta_i sin_i, in the plane of incidence, on the other side.
        const double eta_o = cos_o > 0 ? 1.0 : 1.5, eta_i = cos_o > 0 ? 1.5 : 1.0;
        const double sin_i = std::sqrt(std::max(0.0, 1.0 - static_cast<double>(cos_i) * cos_i));
        EXPECT_NEAR(eta_o * sin_o, eta_i * sin_i, 1e-5);
        EXPECT_NEAR(glm::dot(frame.to_local(s->wi), glm::vec3(0, 1, 0)), 0.0f, 1e-5f) << "left the plane of incidence";
        EXPECT_LT(glm::dot(frame.to_local(s->wi), glm::vec3(1, 0, 0)), 0.0f) << "refracted to the wrong side";
        const float w = static_cast<float>((eta_o / eta_i) * (eta_o / eta_i));  // radiance scales by (eta_o/eta_i)^2
        EXPECT_NEAR(s->weight.x, w, 1e-5f);
      }
    }
    const double sd = std::sqrt(F * (1.0 - F) / n);
    EXPECT_NEAR(static_cast<double>(reflected) / n, F, 4.0 * sd + 1e-9) << "cos_o " << cos_o;
  }
}

TEST(Bsdf, GlassWithIorOnePassesStraightThrough) {
  Material m = make(MaterialType::Glass);
  m.ior = 1.0f;
  const Bsdf bsdf = Bsdf::from_material(m);
  const glm::vec3 ng(0, 0, 1);
  const glm::vec3 wo = glm::normalize(glm::vec3(0.3f, 0.4f, 0.5f));
  for (float u : {0.0f, 0.5f, 0.999f}) {
    const auto s = bsdf.sample(wo, ng, u, {0.5f, 0.5f});
    ASSERT_TRUE(s.has_value());
    EXPECT_NEAR(glm::length(s->wi + wo), 0.0f, 1e-6f);
    EXPECT_EQ(s->weight, glm::vec3(1.0f));
  }
}

TEST(Bsdf, EmissiveWithoutAlbedoAbsorbs) {
  Material m;
  m.type = MaterialType::Emissive;
  m.radiance = glm::vec3(3.0f);
  const Bsdf bsdf = Bsdf::from_material(m);
  EXPECT_TRUE(bsdf.is_black());
  EXPECT_FALSE(bsdf.sample({0, 0, 1}, {0, 0, 1}, 0.5f, {0.5f, 0.5f}).has_value());
  m.albedo = glm::vec3(0.5f);
  EXPECT_FALSE(Bsdf::from_material(m).is_black());
}

TEST(Mis, WeightsOfLightAndBsdfSamplingSumToOne) {
  const float pdfs[] = {0.0f, 1e-30f, 1e-3f, 0.25f, 1.0f, 7.0f, 1e6f, 1e30f};
  for (float light_pdf : pdfs) {
    for (float bsdf_pdf : pdfs) {
      if (light_pdf == 0.0f && bsdf_pdf == 0.0f) continue;  // a direction neither strategy produces
      // The weight sample_direct_light gives a light sample and the weight emission_weight gives the same
      // direction found by BSDF sampling.
      const float w_light = light_pdf > 0.0f ? power_heuristic(1.0f, light_pdf, 1.0f, bsdf_pdf) : 0.0f;
      const float w_bsdf = bsdf_pdf > 0.0f ? emission_weight(SamplingStrategy::Mis, false, bsdf_pdf, light_pdf) : 0.0f;
      EXPECT_NEAR(w_light + w_bsdf, 1.0f, 1e-6f) << light_pdf << " " << bsdf_pdf;
      // Single-strategy modes: exactly one estimator counts each direction it can produce.
      if (light_pdf > 0.0f && bsdf_pdf > 0.0f) {
        EXPECT_EQ(emission_weight(SamplingStrategy::Light, false, bsdf_pdf, light_pdf), 0.0f);
        EXPECT_EQ(emission_weight(SamplingStrategy::Bsdf, false, bsdf_pdf, light_pdf), 1.0f);
      }
    }
  }
  EXPECT_EQ(emission_weight(SamplingStrategy::Mis, true, 1.0f, 5.0f), 1.0f) << "after a delta bounce";
}

}  // namespace
}  // namespace twinray

namespace twinray {
namespace {

// Material::two_sided = false (Mitsuba's BSDFs without `twosided`): the front scatters as before, the back
// is black for evaluation, density and sampling.
TEST(OneSidedBsdf, BackIsBlack) {
  const glm::vec3 ng(0, 0, 1), front(0, 0.6f, 0.8f), back(0, 0.6f, -0.8f), wi_front(0.6f, 0, 0.8f), wi_back(0.6f, 0, -0.8f);
  for (MaterialType type : {MaterialType::Diffuse, MaterialType::Mirror}) {
    Material m;
    m.type = type;
    m.albedo = glm::vec3(0.5f);
    m.reflectance = glm::vec3(0.5f);
    m.two_sided = false;
    const Bsdf one = Bsdf::from_material(m);
    m.two_sided = true;
    const Bsdf two = Bsdf::from_material(m);
    EXPECT_TRUE(one.is_one_sided());
    EXPECT_FALSE(two.is_one_sided());
    EXPECT_TRUE(one.sample(front, ng, 0.5f, {0.3f, 0.7f}).has_value());
    EXPECT_FALSE(one.sample(back, ng, 0.5f, {0.3f, 0.7f}).has_value());
    EXPECT_TRUE(two.sample(back, ng, 0.5f, {0.3f, 0.7f}).has_value());
    EXPECT_EQ(one.eval(back, wi_back, ng), glm::vec3(0.0f));
    EXPECT_EQ(one.pdf(back, wi_back, ng), 0.0f);
    EXPECT_EQ(one.eval(front, wi_front, ng), two.eval(front, wi_front, ng));
    EXPECT_EQ(two.eval(back, wi_back, ng), two.eval(front, wi_front, ng));
  }
}

}  // namespace
}  // namespace twinray
