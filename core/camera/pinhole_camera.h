#pragma once
// Pinhole camera. Camera space: +X right, +Y up, looking down -Z.
//
// generate_ray(u, v) takes (u, v) in [0,1]^2 with u to the right and v UP, so pixel (i, j) with row j
// counted from the top of the image has its centre at u = (i + 0.5)/W, v = 1 - (j + 0.5)/H, and the
// camera-space direction of that centre is
//   normalize(((2(i+0.5)/W - 1) tan(fov/2) A, (1 - 2(j+0.5)/H) tan(fov/2), -1)),   A = W/H.

#include "core/geometry/ray.h"
#include "core/scene/scene.h"

#include <glm/vec3.hpp>

namespace twinray {

class PinholeCamera {
 public:
  explicit PinholeCamera(const CameraDesc& desc);

  Ray generate_ray(float u, float v) const;
  // The ray through the centre of pixel (i, j), row j from the top.
  Ray pixel_center_ray(int i, int j) const;

  int width() const { return width_; }
  int height() const { return height_; }
  const glm::vec3& position() const { return position_; }
  // World-space basis: right, up, and backward (the camera looks down -back).
  const glm::vec3& right() const { return right_; }
  const glm::vec3& up() const { return up_; }
  const glm::vec3& back() const { return back_; }

 private:
  glm::vec3 position_, right_, up_, back_;
  float tan_half_fov_ = 1.0f;
  float aspect_ = 1.0f;
  int width_ = 1, height_ = 1;
};

}  // namespace twinray
