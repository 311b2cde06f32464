#pragma once
// Pinhole camera. Camera space: +X right, +Y up, looking down -Z.
//
// generate_ray(u, v) takes (u, v) in [0,1]^2 with u to the right and v UP, so pixel (i, j) with row j
// counted from the top of the image has its centre at u = (i + 0.5)/W, v = 1 - (j + 0.5)/H, and the
// camera-space direction of that centre is
//   normalize(((2(i+0.5)/W - 1) tan(fov/2) A, (1 - 2(j+0.5)/H) tan(fov/2), -1)),   A = W/H.
//
// Importance (what a light tracer connecting to the camera needs, project()): the image plane at distance 1
// has area A_img = (2 tan(fov/2) A)(2 tan(fov/2)); a pixel's value is the mean radiance over its share of
// that plane, so one pixel's importance is W_e = (W H) / (A_img cos^4 theta) per unit solid angle and
// per unit area of the (point) aperture, with theta the angle between the ray and the viewing axis.
// A point y seen at distance d then receives, per unit incident radiance, W_e cos(theta) / d^2 of the
// pixel's measurement: project() returns that factor without the W H (the film divides splat sums by the
// samples per pixel, not by the number of light paths, which is W H times larger).

#include "core/geometry/ray.h"
#include "core/scene/scene.h"

#include <glm/vec3.hpp>

#include <cstdint>

namespace twinray {

class PinholeCamera {
 public:
  explicit PinholeCamera(const CameraDesc& desc);

  Ray generate_ray(float u, float v) const;
  // The ray through the centre of pixel (i, j), row j from the top.
  Ray pixel_center_ray(int i, int j) const;

  // Where a world point appears on the image, for connecting a light path to the camera.
  struct Projection {
    std::uint32_t x = 0, y = 0;  // pixel, row y from the top
    glm::vec3 to_camera{0.0f};   // unit direction from the point toward the camera
    float distance = 0.0f;       // from the point to the camera position
    float importance = 0.0f;     // 1 / (A_img cos^3 theta d^2): W_e cos(theta) / d^2 without the W H
  };
  // False when the point is behind the camera, on its position, or outside the image.
  bool project(const glm::vec3& point, Projection& out) const;

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
  float image_plane_area_ = 4.0f;  // A_img at distance 1
  float aspect_ = 1.0f;
  int width_ = 1, height_ = 1;
};

}  // namespace twinray
