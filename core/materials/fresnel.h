#pragma once
// Exact Fresnel reflectance of a smooth dielectric interface for unpolarised light.
//
// The reflectance is the mean of the s- and p-polarised Fresnel equations; there is no Schlick
// approximation here because the white-furnace and ior = 1 tests expect exact energy balance.

#include <algorithm>
#include <cmath>

namespace twinray {

struct FresnelResult {
  float reflectance = 1.0f;  // in [0, 1]; 1 on total internal reflection
  float cos_t = 0.0f;        // cosine of the refracted direction with the normal (>= 0); 0 on TIR
  float eta_ti = 1.0f;       // relative index eta_transmitted / eta_incident
};

// `cos_i` is the cosine between the incident direction (pointing away from the surface) and the normal
// whose positive side is the exterior; `ior` is the interior index over the exterior one. A negative
// cos_i means the direction lies inside, so the roles of the two media are swapped.
inline FresnelResult fresnel_dielectric(float cos_i, float ior) {
  FresnelResult r;
  float eta = ior;
  if (cos_i < 0.0f) {
    eta = 1.0f / ior;
    cos_i = -cos_i;
  }
  cos_i = std::min(cos_i, 1.0f);
  r.eta_ti = eta;
  if (eta == 1.0f) {
    // Index-matched: there is no interface. Exact, where the general formula leaves ~1e-15 of rounding.
    r.reflectance = 0.0f;
    r.cos_t = cos_i;
    return r;
  }
  const float sin2_t = (1.0f - cos_i * cos_i) / (eta * eta);
  if (sin2_t >= 1.0f) return r;  // total internal reflection
  const float cos_t = std::sqrt(std::max(0.0f, 1.0f - sin2_t));
  const float r_parallel = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
  const float r_perpendicular = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
  r.reflectance = std::clamp(0.5f * (r_parallel * r_parallel + r_perpendicular * r_perpendicular), 0.0f, 1.0f);
  r.cos_t = cos_t;
  return r;
}

}  // namespace twinray
