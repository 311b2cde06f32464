#pragma once
// The closed set of surface scattering models, dispatched by a switch on MaterialType.
//
// Conventions (all vectors in world space, unit length):
//  - `wo` points away from the surface toward where the light goes (the previous path vertex),
//    `wi` points away from the surface toward where the light comes from.
//  - Only geometric normals exist. `ng` is the unit geometric normal as the backend reports it (never
//    flipped). Opaque models (diffuse, mirror) are two-sided by default: they use the side of `ng` that `wo`
//    is on. A one-sided one (Material::two_sided = false, Mitsuba's BSDFs without `twosided`) scatters
//    only on the front (wo on the positive side of ng) and is black seen from the back.
//    Glass uses `ng` to tell outside (the positive side) from inside.
//  - eval() returns f(wo, wi) |cos(ng, wi)|, the quantity the estimators multiply by radiance.
//  - Delta models (mirror, glass) have eval() = pdf() = 0: they can only be sampled.
//
// Emissive materials scatter like a Lambertian surface with their optional albedo (zero by default,
// which makes the surface a pure emitter that ends paths).

#include "core/materials/fresnel.h"
#include "core/sampling/warp.h"
#include "core/scene/scene.h"

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <numbers>
#include <optional>

namespace twinray {

struct BsdfSample {
  glm::vec3 wi{0.0f};
  glm::vec3 weight{0.0f};  // f |cos| / pdf: what the path throughput is multiplied by
  float pdf = 0.0f;        // solid-angle density; for delta lobes the probability of the chosen lobe
  bool delta = false;      // true for mirror and glass: no light sampling, emission counts fully
  float eta_ti = 1.0f;     // relative index crossed (1 unless refracted): undone for Russian roulette
};

class Bsdf {
 public:
  enum class Kind { Lambertian, Mirror, Dielectric, Black };

  static Bsdf from_material(const Material& m) {
    Bsdf b;
    switch (m.type) {
      case MaterialType::Diffuse: b.kind_ = Kind::Lambertian; b.tint_ = m.albedo; break;
      case MaterialType::Mirror: b.kind_ = Kind::Mirror; b.tint_ = m.reflectance; break;
      case MaterialType::Glass: b.kind_ = Kind::Dielectric; b.tint_ = glm::vec3(1.0f); b.ior_ = m.ior; break;
      case MaterialType::Emissive:
        b.kind_ = Kind::Lambertian;
        b.tint_ = m.albedo;
        break;
    }
    if (b.kind_ == Kind::Lambertian && b.tint_.x <= 0.0f && b.tint_.y <= 0.0f && b.tint_.z <= 0.0f)
      b.kind_ = Kind::Black;
    b.one_sided_ = !m.two_sided && (b.kind_ == Kind::Lambertian || b.kind_ == Kind::Mirror);
    return b;
  }

  Kind kind() const { return kind_; }
  bool is_delta() const { return kind_ == Kind::Mirror || kind_ == Kind::Dielectric; }
  bool is_black() const { return kind_ == Kind::Black; }
  bool is_one_sided() const { return one_sided_; }
  // Hemispherical reflectance seen by the albedo AOV (glass reports 1).
  glm::vec3 albedo() const { return kind_ == Kind::Black ? glm::vec3(0.0f) : tint_; }

  glm::vec3 eval(const glm::vec3& wo, const glm::vec3& wi, const glm::vec3& ng) const {
    if (kind_ != Kind::Lambertian) return glm::vec3(0.0f);
    const float cos_o = glm::dot(wo, ng), cos_i = glm::dot(wi, ng);
    if (!same_side(cos_o, cos_i) || (one_sided_ && !(cos_o > 0.0f))) return glm::vec3(0.0f);
    return tint_ * (std::abs(cos_i) * std::numbers::inv_pi_v<float>);
  }

  // eval() and pdf() at once (what a light sample's MIS weight needs): one pair of dot products.
  glm::vec3 eval(const glm::vec3& wo, const glm::vec3& wi, const glm::vec3& ng, float& pdf_out) const {
    pdf_out = 0.0f;
    if (kind_ != Kind::Lambertian) return glm::vec3(0.0f);
    const float cos_o = glm::dot(wo, ng), cos_i = glm::dot(wi, ng);
    if (!same_side(cos_o, cos_i) || (one_sided_ && !(cos_o > 0.0f))) return glm::vec3(0.0f);
    pdf_out = std::abs(cos_i) * std::numbers::inv_pi_v<float>;
    return tint_ * pdf_out;
  }

  float pdf(const glm::vec3& wo, const glm::vec3& wi, const glm::vec3& ng) const {
    if (kind_ != Kind::Lambertian) return 0.0f;
    const float cos_o = glm::dot(wo, ng), cos_i = glm::dot(wi, ng);
    if (!same_side(cos_o, cos_i) || (one_sided_ && !(cos_o > 0.0f))) return 0.0f;
    return std::abs(cos_i) * std::numbers::inv_pi_v<float>;
  }

  // One 2D value drives every kind: the direction of a Lambertian sample, or (u.x) the lobe of the
  // dielectric; each kind uses only what it needs, so one sampler dimension serves every vertex.
  // False when nothing is scattered (grazing, the black back of a one-sided surface, black); `out` is then
  // unspecified. This is the form the integrators call; the optional ones below wrap it.
  [[gnu::always_inline]] bool sample(const glm::vec3& wo, const glm::vec3& ng, glm::vec2 u, BsdfSample& out) const {
    return sample(wo, ng, u.x, u, out);
  }
  std::optional<BsdfSample> sample(const glm::vec3& wo, const glm::vec3& ng, glm::vec2 u) const {
    return sample(wo, ng, u.x, u);
  }
  // `u_lobe` chooses between reflection and refraction (glass); `u` drives the direction.
  std::optional<BsdfSample> sample(const glm::vec3& wo, const glm::vec3& ng, float u_lobe, glm::vec2 u) const {
    BsdfSample s;
    if (!sample(wo, ng, u_lobe, u, s)) return std::nullopt;
    return s;
  }

  // Both forms that the integrators reach are forced inline: GCC kept them out of the path integrator's loop
  // (2% of the render's instructions, docs/rendering.md).
  [[gnu::always_inline]] bool sample(const glm::vec3& wo, const glm::vec3& ng, float u_lobe, glm::vec2 u,
                                     BsdfSample& s) const {
    const float cos_o = glm::dot(wo, ng);
    if (cos_o == 0.0f) return false;  // grazing: no side to scatter into
    if (one_sided_ && cos_o < 0.0f) return false;  // the black back of a one-sided surface
    switch (kind_) {
      case Kind::Lambertian: {
        const glm::vec3 n = cos_o > 0.0f ? ng : -ng;
        const glm::vec3 local = sample_cosine_hemisphere(u);
        s.wi = glm::normalize(Frame::from_normal(n).to_world(local));
        const float cos_i = glm::dot(s.wi, n);
        s.pdf = cos_i * std::numbers::inv_pi_v<float>;
        s.weight = tint_;  // (albedo/pi) cos / (cos/pi)
        s.delta = false;
        s.eta_ti = 1.0f;
        return cos_i > 0.0f;
      }
      case Kind::Mirror:
        s.wi = reflect(wo, ng, cos_o);
        s.pdf = 1.0f;
        s.delta = true;
        s.weight = tint_;
        s.eta_ti = 1.0f;
        return true;
      case Kind::Dielectric: sample_dielectric(wo, ng, cos_o, u_lobe, s); return true;
      case Kind::Black: return false;
    }
    return false;
  }

 private:
  static bool same_side(float cos_o, float cos_i) {
    return (cos_o > 0.0f && cos_i > 0.0f) || (cos_o < 0.0f && cos_i < 0.0f);
  }
  static glm::vec3 reflect(const glm::vec3& wo, const glm::vec3& n, float cos_o) {
    return glm::normalize(2.0f * cos_o * n - wo);
  }

  void sample_dielectric(const glm::vec3& wo, const glm::vec3& ng, float cos_o, float u_lobe, BsdfSample& s) const {
    const FresnelResult fr = fresnel_dielectric(cos_o, ior_);
    s.delta = true;
    // Choosing the lobe with probability F (reflect) or 1 - F (refract) makes the weight exactly 1 for
    // reflection; refraction carries the 1/eta^2 radiance compression of crossing the interface.
    if (u_lobe < fr.reflectance) {
      s.wi = reflect(wo, ng, cos_o);
      s.pdf = fr.reflectance;
      s.weight = glm::vec3(1.0f);
      s.eta_ti = 1.0f;
      return;
    }
    // Refraction (Snell's law in vector form, with n on the side of wo).
    const glm::vec3 n = cos_o > 0.0f ? ng : -ng;
    const float eta = fr.eta_ti;
    const float cos_i = std::abs(cos_o);
    s.wi = glm::normalize(-wo / eta + (cos_i / eta - fr.cos_t) * n);
    s.pdf = 1.0f - fr.reflectance;
    s.eta_ti = eta;
    s.weight = glm::vec3(1.0f / (eta * eta));
  }

  Kind kind_ = Kind::Black;
  bool one_sided_ = false;
  glm::vec3 tint_{0.0f};
  float ior_ = 1.0f;
};

}  // namespace twinray
