#pragma once
// Where a plugin is wrong, at a glance: the scene shaded from the reference's camera hits (grey by the
// cosine between surface normal and ray, a dark blue background where nothing is hit), with every pixel
// whose answer the check judged wrong painted red.

#include "core/geometry/hit.h"
#include "core/geometry/ray.h"
#include "core/image/image.h"
#include "harness/grade/answers.h"

#include <span>

namespace twinray::grade {

// `rays` and `reference` hold one entry per pixel, row by row from the top (grade_rays.h's PixelRays);
// wrong answers for rays beyond the image are ignored. A small image is enlarged by an integer factor (each
// ray a square of pixels) until its longer side reaches kMinImageSide, so that single wrong rays show.
inline constexpr int kMinImageSide = 512;
Image disagreement_image(int width, int height, std::span<const Ray> rays, std::span<const Hit> reference,
                         std::span<const WrongAnswer> wrong);

}  // namespace twinray::grade
