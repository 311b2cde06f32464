#include "core/camera/pinhole_camera.h"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace twinray {

PinholeCamera::PinholeCamera(const CameraDesc& desc)
    : position_(desc.position), width_(desc.width), height_(desc.height) {
  if (desc.width <= 0 || desc.height <= 0) throw std::invalid_argument("camera resolution must be positive");
  if (!(desc.vfov_deg > 0.0f && desc.vfov_deg < 180.0f))
    throw std::invalid_argument("camera field of view must be in (0, 180) degrees");
  // The frame in double: the squared length of a float difference neither overflows nor underflows there, so
  // a scene at 1e30 or at 1e-30 (any finite float coordinates) gets the same frame as one at 1.
  const glm::dvec3 forward = glm::dvec3(desc.look_at) - glm::dvec3(desc.position);
  if (glm::dot(forward, forward) == 0.0) throw std::invalid_argument("camera look_at equals position");
  const glm::dvec3 back = -glm::normalize(forward);
  const glm::dvec3 up_hint = glm::dvec3(desc.up);
  if (!(glm::dot(up_hint, up_hint) > 0.0)) throw std::invalid_argument("camera up is the zero vector");
  const glm::dvec3 r = glm::cross(glm::normalize(up_hint), back);
  if (!(glm::dot(r, r) > 0.0)) throw std::invalid_argument("camera up is parallel to the viewing direction");
  const glm::dvec3 right = glm::normalize(r);
  back_ = glm::vec3(back);
  right_ = glm::vec3(right);
  up_ = glm::vec3(glm::cross(back, right));
  tan_half_fov_ = std::tan(0.5f * desc.vfov_deg * 3.14159265358979323846f / 180.0f);
  aspect_ = static_cast<float>(width_) / static_cast<float>(height_);
  image_plane_area_ = 4.0f * tan_half_fov_ * tan_half_fov_ * aspect_;
}

Ray PinholeCamera::generate_ray(float u, float v) const {
  const float x = (2.0f * u - 1.0f) * tan_half_fov_ * aspect_;
  const float y = (2.0f * v - 1.0f) * tan_half_fov_;
  Ray ray;
  ray.org = position_;
  ray.dir = glm::normalize(x * right_ + y * up_ - back_);
  ray.tmin = 0.0f;
  ray.tmax = std::numeric_limits<float>::infinity();
  return ray;
}

Ray PinholeCamera::pixel_center_ray(int i, int j) const {
  return generate_ray((static_cast<float>(i) + 0.5f) / static_cast<float>(width_),
                      1.0f - (static_cast<float>(j) + 0.5f) / static_cast<float>(height_));
}

}  // namespace twinray

namespace twinray {

bool PinholeCamera::project(const glm::vec3& point, Projection& out) const {
  const glm::vec3 d = point - position_;
  if (!std::isfinite(d.x) || !std::isfinite(d.y) || !std::isfinite(d.z)) return false;
  // In double: a float dist2 overflows beyond 1.8e19 and underflows below 1e-19 (scenes far from 1 in scale).
  const double dist2 = glm::dot(glm::dvec3(d), glm::dvec3(d));
  if (!(dist2 > 0.0)) return false;
  const float z = -glm::dot(d, back_);  // depth along the viewing axis
  if (!(z > 0.0f)) return false;
  // (u, v) as generate_ray takes them: x / z = (2u - 1) tan(fov/2) A, y / z = (2v - 1) tan(fov/2).
  const float u = 0.5f * (glm::dot(d, right_) / (z * tan_half_fov_ * aspect_) + 1.0f);
  const float v = 0.5f * (glm::dot(d, up_) / (z * tan_half_fov_) + 1.0f);
  const float px = u * static_cast<float>(width_);
  const float py = (1.0f - v) * static_cast<float>(height_);
  // Half-open pixel ranges [0, W) x [0, H), as the camera's jittered samples cover them.
  if (!(px >= 0.0f && px < static_cast<float>(width_) && py >= 0.0f && py < static_cast<float>(height_))) return false;
  out.x = std::min(static_cast<std::uint32_t>(px), static_cast<std::uint32_t>(width_ - 1));
  out.y = std::min(static_cast<std::uint32_t>(py), static_cast<std::uint32_t>(height_ - 1));
  const double dist = std::sqrt(dist2);
  out.distance = static_cast<float>(dist);
  out.to_camera = glm::vec3(-glm::dvec3(d) / dist);
  const double cos_theta = double(z) / dist;
  out.importance = static_cast<float>(1.0 / (double(image_plane_area_) * cos_theta * cos_theta * cos_theta * dist2));
  return std::isfinite(out.importance) && out.importance > 0.0f;
}

}  // namespace twinray
