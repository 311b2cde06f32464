#include "core/lights/area_lights.h"

#include "core/intersect/sphere_robust.h"
#include "core/sampling/warp.h"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>

namespace twinray {
namespace {

float luminance(const glm::vec3& c) { return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z; }

// A receiving point counts as outside a sphere (cone sampling) only when it is clearly off the surface:
// points on the surface itself (an emissive sphere with an albedo lighting itself) would see a cone of
// half-angle ~90 degrees whose near intersection is the point itself. The relative margin is far above the
// rounding of |ref - center|^2 and far below any geometric scale that matters for sampling efficiency.
constexpr float kOutsideMargin = 1e-3f;
bool outside_sphere(float dist2, float radius) { return dist2 > radius * radius * (1.0f + kOutsideMargin); }

}  // namespace

LightSampler::LightSampler(const Scene& scene, const EnvironmentLight* env) {
  std::vector<float> power;
  first_light_of_geom_.assign(scene.geometry.geom_id_end(), kNone);

  for (const TriangleMesh& mesh : scene.geometry.meshes) {
    const Material& m = scene.material_of(mesh.geom_id);
    if (m.type != MaterialType::Emissive || !(luminance(m.radiance) > 0.0f) || mesh.indices.empty()) continue;
    first_light_of_geom_[mesh.geom_id] = static_cast<std::uint32_t>(triangles_.size());
    for (const glm::uvec3& idx : mesh.indices) {
      EmissiveTriangle t;
      t.p0 = mesh.positions[idx.x];
      t.e1 = mesh.positions[idx.y] - t.p0;
      t.e2 = mesh.positions[idx.z] - t.p0;
      const glm::vec3 c = glm::cross(t.e1, t.e2);
      const float len = glm::length(c);
      t.area = 0.5f * len;
      // Loaders drop degenerate triangles, but a cross product can still underflow for a tiny one: keep the
      // index layout (light = first + prim_id) and give it zero power so it is never chosen.
      t.normal = len > 0.0f ? c / len : glm::vec3(0.0f, 1.0f, 0.0f);
      t.radiance = m.radiance;
      triangles_.push_back(t);
      power.push_back(len > 0.0f ? kPi * t.area * luminance(m.radiance) : 0.0f);
    }
  }
  // Sphere light indices continue after all triangles.
  std::vector<std::pair<std::uint32_t, EmissiveSphere>> sphere_lights;
  for (const Sphere& s : scene.geometry.spheres) {
    const Material& m = scene.material_of(s.geom_id);
    if (m.type != MaterialType::Emissive || !(luminance(m.radiance) > 0.0f) || !(s.radius > 0.0f)) continue;
    sphere_lights.push_back({s.geom_id, EmissiveSphere{s.center, s.radius, m.radiance}});
  }
  for (const auto& [geom_id, sph] : sphere_lights) {
    first_light_of_geom_[geom_id] = static_cast<std::uint32_t>(triangles_.size() + spheres_.size());
    spheres_.push_back(sph);
    power.push_back(kPi * 4.0f * kPi * sph.radius * sph.radius * luminance(sph.radiance));
  }
  if (env != nullptr && luminance(env->average_radiance()) > 0.0f) {
    env_ = env;
    env_index_ = static_cast<std::uint32_t>(power.size());
    // Half of the choices when there are surface lights (see area_lights.h), all of them otherwise.
    float surface_power = 0.0f;
    for (float p : power) surface_power += p;
    power.push_back(surface_power > 0.0f ? surface_power : 1.0f);
  }
  if (!power.empty()) {
    float total = 0.0f;
    for (float p : power) total += p;
    if (total > 0.0f && std::isfinite(total)) selection_.emplace(power);
  }
  if (selection_) {
    const std::size_t n = selection_->size();
    pmf_.resize(n);
    for (std::size_t i = 0; i < n; ++i) pmf_[i] = selection_->pmf(i);
    double surface = 0.0;
    for (std::size_t i = 0; i < n; ++i)
      if (i != env_index_) surface += static_cast<double>(pmf_[i]);
    surface_fraction_ = static_cast<float>(surface);
    emission_pdf_area_.assign(n, 0.0f);
    for (std::size_t i = 0; i < n && surface_fraction_ > 0.0f; ++i) {
      const float area = i < triangles_.size() ? triangles_[i].area
                         : i - triangles_.size() < spheres_.size()
                             ? 4.0f * kPi * spheres_[i - triangles_.size()].radius * spheres_[i - triangles_.size()].radius
                             : 0.0f;
      if (area > 0.0f) emission_pdf_area_[i] = pmf_[i] / surface_fraction_ / area;
    }
    if (n <= kFewLights) {
      cdf_.assign(n + 1, 0.0f);
      double running = 0.0;
      for (std::size_t i = 0; i < n; ++i) {
        running += static_cast<double>(selection_->weight(i));
        cdf_[i + 1] = static_cast<float>(running / selection_->weight_sum());
      }
      cdf_[n] = 1.0f;
      inv_width_.assign(n, 0.0f);
      for (std::size_t i = 0; i < n; ++i) {
        const double width = static_cast<double>(cdf_[i + 1]) - static_cast<double>(cdf_[i]);
        inv_width_[i] = width > 0.0 ? static_cast<float>(1.0 / width) : 0.0f;
      }
    }
  }
}

float LightSampler::selection_probability(std::size_t light_index) const {
  return selection_ ? selection_->pmf(light_index) : 0.0f;
}

std::optional<LightSample> LightSampler::sample(const glm::vec3& ref, glm::vec2 u) const {
  LightSample s;
  if (!sample(ref, u, s)) return std::nullopt;
  return s;
}

std::optional<LightSample> LightSampler::sample(const glm::vec3& ref, float u_select, glm::vec2 u) const {
  if (!selection_) return std::nullopt;
  float pmf = 0.0f;
  const std::size_t i = selection_->sample_discrete(u_select, &pmf);
  LightSample s;
  if (!sample_light(i, pmf, ref, u, s)) return std::nullopt;
  return s;
}

void LightSampler::sample_sphere(const EmissiveSphere& sph, const glm::vec3& ref, glm::vec2 u, LightSample& s) {
  const glm::vec3 to_center = sph.center - ref;
  const float dist2 = glm::dot(to_center, to_center);
  if (outside_sphere(dist2, sph.radius)) {
    const float one_minus_cos = one_minus_cos_from_sin2(sph.radius * sph.radius / dist2);
    const glm::vec3 axis = to_center / std::sqrt(dist2);
    s.wi = glm::normalize(Frame::from_normal(axis).to_world(sample_uniform_cone_one_minus_cos(u, one_minus_cos)));
    // The point where the sampled direction enters the sphere, in double (sphere_robust.h). A direction on
    // the rim can miss by rounding: then the point of closest approach, pushed onto the surface, stands in.
    double t0 = 0.0, t1 = 0.0;
    double t = glm::dot(to_center, s.wi);
    if (sphere_detail::sphere_roots(ref, s.wi, sph.center, sph.radius, t0, t1) && t0 > 0.0) t = t0;
    const glm::vec3 p = ref + static_cast<float>(t) * s.wi;
    s.normal = glm::normalize(p - sph.center);
    s.point = sph.center + sph.radius * s.normal;
    s.radiance = sph.radiance;  // seen from outside: always the emitting side
    s.pdf = uniform_cone_pdf_one_minus_cos(one_minus_cos);
    return;
  }
  s.normal = sample_uniform_sphere(u);
  s.point = sph.center + sph.radius * s.normal;
  const glm::vec3 d = s.point - ref;
  const float d2 = glm::dot(d, d);
  if (!(d2 > 0.0f)) return;
  s.wi = d / std::sqrt(d2);
  const float cos_light = -glm::dot(s.normal, s.wi);
  // From inside, the inner (back) side faces ref: no emission, but the pdf stays what sampling produced.
  s.radiance = cos_light > 0.0f ? sph.radiance : glm::vec3(0.0f);
  s.pdf = std::abs(cos_light) > 0.0f ? d2 / (std::abs(cos_light) * 4.0f * kPi * sph.radius * sph.radius) : 0.0f;
}

float LightSampler::sphere_pdf(const EmissiveSphere& sph, const glm::vec3& ref, const glm::vec3& point,
                               const glm::vec3& normal) {
  const glm::vec3 to_center = sph.center - ref;
  const float dist2 = glm::dot(to_center, to_center);
  if (outside_sphere(dist2, sph.radius))
    return uniform_cone_pdf_one_minus_cos(one_minus_cos_from_sin2(sph.radius * sph.radius / dist2));
  const glm::vec3 d = point - ref;
  const float d2 = glm::dot(d, d);
  const float cos_light = std::abs(glm::dot(normal, d)) / std::sqrt(d2);
  if (!(cos_light > 0.0f)) return 0.0f;
  return d2 / (cos_light * 4.0f * kPi * sph.radius * sph.radius);
}

float LightSampler::pdf_surface(const glm::vec3& ref, const Hit& hit, const glm::vec3& point) const {
  if (!selection_ || hit.geom_id >= first_light_of_geom_.size()) return 0.0f;
  const std::uint32_t first = first_light_of_geom_[hit.geom_id];
  if (first == kNone) return 0.0f;
  return pdf_light(first < triangles_.size() ? first + hit.prim_id : first, ref, point, hit.ng);
}

float LightSampler::pdf_light(std::size_t i, const glm::vec3& ref, const glm::vec3& point,
                               const glm::vec3& normal) const {
  if (!selection_ || i >= pmf_.size()) return 0.0f;
  if (i < triangles_.size()) {
    const EmissiveTriangle& tri = triangles_[i];
    const glm::vec3 d = point - ref;
    const float dist2 = glm::dot(d, d);
    const float cos_light = std::abs(glm::dot(tri.normal, d)) / std::sqrt(dist2);
    if (!(cos_light > 0.0f) || !(tri.area > 0.0f)) return 0.0f;
    return pmf_[i] * dist2 / (cos_light * tri.area);
  }
  if (i - triangles_.size() < spheres_.size()) return pmf_[i] * sphere_pdf(spheres_[i - triangles_.size()], ref, point, normal);
  return 0.0f;
}

float LightSampler::emission_pdf_area(const Hit& hit) const {
  if (!selection_ || hit.geom_id >= first_light_of_geom_.size()) return 0.0f;
  const std::uint32_t first = first_light_of_geom_[hit.geom_id];
  if (first == kNone) return 0.0f;
  return emission_pdf_area(first < triangles_.size() ? first + hit.prim_id : first);
}

float LightSampler::pdf_environment(const glm::vec3& dir) const {
  if (!selection_ || env_ == nullptr || env_index_ == kNone) return 0.0f;
  return pmf_[env_index_] * env_->pdf(dir);
}

bool LightSampler::sample_emission(glm::vec2 u_point, glm::vec2 u_dir, EmissionSample& out) const {
  if (!has_surface_lights()) return false;
  // The surface lights come first in selection order, so scaling u into [0, surface fraction) picks among
  // them with probability pmf / surface fraction. The clamp keeps u below the environment's step.
  const float u_select = std::min(u_point.x * surface_fraction_, std::nextafter(surface_fraction_, 0.0f));
  float pmf = 0.0f, rest = 0.0f;
  const std::size_t i = select_light(std::max(u_select, 0.0f), pmf, rest);
  if (i >= triangles_.size() + spheres_.size() || !(pmf > 0.0f)) return false;
  const float pmf_surface = pmf / surface_fraction_;
  const glm::vec2 u(std::min(std::max(rest, 0.0f), 0x1.fffffep-1f), u_point.y);
  float area = 0.0f;
  glm::vec3 radiance(0.0f);
  if (i < triangles_.size()) {
    const EmissiveTriangle& tri = triangles_[i];
    const glm::vec3 b = sample_uniform_triangle(u);
    out.point = tri.p0 + b.y * tri.e1 + b.z * tri.e2;
    out.normal = tri.normal;
    const glm::vec3 p1 = tri.p0 + tri.e1, p2 = tri.p0 + tri.e2;
    const glm::vec3 m = glm::max(glm::abs(tri.p0), glm::max(glm::abs(p1), glm::abs(p2)));
    out.error_scale = std::max(m.x, std::max(m.y, m.z));
    area = tri.area;
    radiance = tri.radiance;
  } else {
    const EmissiveSphere& sph = spheres_[i - triangles_.size()];
    out.normal = sample_uniform_sphere(u);
    out.point = sph.center + sph.radius * out.normal;
    const glm::vec3 c = glm::abs(sph.center);
    out.error_scale = std::max(c.x, std::max(c.y, c.z)) + sph.radius;
    area = 4.0f * kPi * sph.radius * sph.radius;
    radiance = sph.radiance;
  }
  if (!(area > 0.0f)) return false;
  out.dir = glm::normalize(Frame::from_normal(out.normal).to_world(sample_cosine_hemisphere(u_dir)));
  if (!(glm::dot(out.dir, out.normal) > 0.0f)) return false;
  // Le cos / (pdf_area cos / pi) with pdf_area = pmf_surface / area.
  out.light = static_cast<std::uint32_t>(i);
  out.pdf_area = emission_pdf_area_[i];
  out.weight = radiance * (kPi * area / pmf_surface);
  return std::isfinite(out.weight.x) && std::isfinite(out.weight.y) && std::isfinite(out.weight.z);
}

}  // namespace twinray
