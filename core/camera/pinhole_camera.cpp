#include "core/camera/pinhole_camera.h"

#include <glm/geometric.hpp>

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
