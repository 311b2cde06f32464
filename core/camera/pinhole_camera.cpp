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
  const glm::vec3 forward = desc.look_at - desc.position;
  if (glm::dot(forward, forward) == 0.0f) throw std::invalid_argument("camera look_at equals position");
  back_ = -glm::normalize(forward);
  const glm::vec3 r = glm::cross(desc.up, back_);
  if (!(glm::dot(r, r) > 0.0f)) throw std::invalid_argument("camera up is parallel to the viewing direction");
  right_ = glm::normalize(r);
  up_ = glm::cross(back_, right_);
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
  const float dist2 = glm::dot(d, d);
  if (!(dist2 > 0.0f) || !std::isfinite(dist2)) return false;
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
  const float dist = std::sqrt(dist2);
  out.distance = dist;
  out.to_camera = -d / dist;
  const float cos_theta = z / dist;
  out.importance = 1.0f / (image_plane_area_ * cos_theta * cos_theta * cos_theta * dist2);
  return std::isfinite(out.importance);
}

}  // namespace twinray
