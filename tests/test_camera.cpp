// The pinhole camera against the closed-form direction of a pixel centre (issue: camera rays).

#include "core/camera/pinhole_camera.h"

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include <cmath>

namespace twinray {
namespace {

// Camera-space direction of pixel (i, j)'s centre, straight from the specification.
glm::dvec3 closed_form(int i, int j, int w, int h, double fov_deg) {
  const double t = std::tan(0.5 * fov_deg * M_PI / 180.0);
  const double a = double(w) / double(h);
  return glm::normalize(glm::dvec3((2.0 * (i + 0.5) / w - 1.0) * t * a, (1.0 - 2.0 * (j + 0.5) / h) * t, -1.0));
}

void expect_matches_closed_form(const CameraDesc& desc) {
  const PinholeCamera cam(desc);
  // World -> camera space with the camera's own basis; the basis itself is checked separately below.
  const glm::dvec3 r = cam.right(), u = cam.up(), b = cam.back();
  for (int j = 0; j < desc.height; j += std::max(1, desc.height / 7)) {
    for (int i = 0; i < desc.width; i += std::max(1, desc.width / 9)) {
      const Ray ray = cam.pixel_center_ray(i, j);
      const glm::dvec3 d = ray.dir;
      const glm::dvec3 local(glm::dot(d, r), glm::dot(d, u), glm::dot(d, b));
      const glm::dvec3 expected = closed_form(i, j, desc.width, desc.height, desc.vfov_deg);
      // Float evaluation of a unit vector: a few ulps per component.
      EXPECT_NEAR(local.x, expected.x, 4e-7) << "pixel " << i << "," << j;
      EXPECT_NEAR(local.y, expected.y, 4e-7) << "pixel " << i << "," << j;
      EXPECT_NEAR(local.z, expected.z, 4e-7) << "pixel " << i << "," << j;
      EXPECT_EQ(ray.org, desc.position);
      EXPECT_EQ(ray.tmin, 0.0f);
      EXPECT_TRUE(std::isinf(ray.tmax));
    }
  }
}

TEST(Camera, PixelCentresMatchClosedFormSquare) {
  CameraDesc d;
  d.position = {0.0f, 0.0f, 3.9f};
  d.look_at = {0.0f, 0.0f, 0.0f};
  d.vfov_deg = 39.3077f;
  d.width = d.height = 256;
  expect_matches_closed_form(d);
}

TEST(Camera, PixelCentresMatchClosedFormWideAndTilted) {
  CameraDesc d;
  d.position = {2.0f, 3.0f, -4.0f};
  d.look_at = {-1.0f, 0.5f, 2.0f};
  d.up = {0.1f, 1.0f, 0.2f};  // not orthogonal to the view: the camera orthonormalises it
  d.vfov_deg = 75.0f;
  d.width = 640;
  d.height = 360;
  expect_matches_closed_form(d);
}

TEST(Camera, BasisIsOrthonormalAndLooksAtTarget) {
  CameraDesc d;
  d.position = {1.0f, 2.0f, 3.0f};
  d.look_at = {4.0f, -1.0f, 0.5f};
  d.up = {0.0f, 1.0f, 0.0f};
  const PinholeCamera cam(d);
  EXPECT_NEAR(glm::length(cam.right()), 1.0f, 1e-6f);
  EXPECT_NEAR(glm::length(cam.up()), 1.0f, 1e-6f);
  EXPECT_NEAR(glm::length(cam.back()), 1.0f, 1e-6f);
  EXPECT_NEAR(glm::dot(cam.right(), cam.up()), 0.0f, 1e-6f);
  EXPECT_NEAR(glm::dot(cam.up(), cam.back()), 0.0f, 1e-6f);
  const glm::vec3 forward = glm::normalize(d.look_at - d.position);
  EXPECT_NEAR(glm::dot(-cam.back(), forward), 1.0f, 1e-6f);
  // The image centre looks straight at the target; +u goes right, +v goes up.
  const Ray centre = cam.generate_ray(0.5f, 0.5f);
  EXPECT_NEAR(glm::dot(centre.dir, forward), 1.0f, 1e-6f);
  EXPECT_GT(glm::dot(cam.generate_ray(1.0f, 0.5f).dir, cam.right()), 0.0f);
  EXPECT_GT(glm::dot(cam.generate_ray(0.5f, 1.0f).dir, cam.up()), 0.0f);
}

TEST(Camera, CornersSpanTheFieldOfView) {
  CameraDesc d;
  d.vfov_deg = 60.0f;
  d.width = 200;
  d.height = 100;
  const PinholeCamera cam(d);
  // v = 1 is the top edge: the angle to the view axis is exactly fov/2.
  const Ray top = cam.generate_ray(0.5f, 1.0f);
  EXPECT_NEAR(std::acos(glm::dot(top.dir, -cam.back())), 30.0 * M_PI / 180.0, 1e-6);
  const Ray right = cam.generate_ray(1.0f, 0.5f);
  EXPECT_NEAR(std::atan2(glm::dot(right.dir, cam.right()), glm::dot(right.dir, -cam.back())),
              std::atan(2.0 * std::tan(30.0 * M_PI / 180.0)), 1e-6);
}

TEST(Camera, RejectsDegenerateSetups) {
  CameraDesc d;
  d.width = 0;
  EXPECT_THROW(PinholeCamera{d}, std::invalid_argument);
  d = {};
  d.look_at = d.position;
  EXPECT_THROW(PinholeCamera{d}, std::invalid_argument);
  d = {};
  d.position = {0, 5, 0};
  d.look_at = {0, 0, 0};
  d.up = {0, 1, 0};
  EXPECT_THROW(PinholeCamera{d}, std::invalid_argument);
  d = {};
  d.vfov_deg = 180.0f;
  EXPECT_THROW(PinholeCamera{d}, std::invalid_argument);
}

// The frame depends on directions only: a setup scaled by a power of two anywhere in float's range (2^-120 to
// 2^126, where a float dot product of the view vector under- or overflows) gives the unit scale's frame bit
// for bit, and its rays the same directions. Scene files at 1e30 or 1e-30 used to be refused ("up is parallel
// to the viewing direction", "look_at equals position").
TEST(Camera, FrameIsTheSameAtEveryScale) {
  CameraDesc unit;
  unit.position = {1.0f, 2.0f, 3.0f};
  unit.look_at = {-0.5f, 0.25f, -1.0f};
  unit.up = {0.0f, 1.0f, 0.0f};
  const PinholeCamera reference(unit);
  for (const int exponent : {-120, -100, -64, 64, 100, 126}) {
    CameraDesc d = unit;
    for (int a = 0; a < 3; ++a) {
      d.position[a] = std::ldexp(unit.position[a], exponent);
      d.look_at[a] = std::ldexp(unit.look_at[a], exponent);
    }
    const PinholeCamera cam(d);
    EXPECT_EQ(cam.back(), reference.back()) << "2^" << exponent;
    EXPECT_EQ(cam.right(), reference.right()) << "2^" << exponent;
    EXPECT_EQ(cam.up(), reference.up()) << "2^" << exponent;
    EXPECT_EQ(cam.pixel_center_ray(3, 7).dir, reference.pixel_center_ray(3, 7).dir) << "2^" << exponent;
  }
}

}  // namespace
}  // namespace twinray
