#pragma once
// Reading and writing images. Every failure throws InputError naming the file.
//
// Writes are atomic from a reader's point of view: the image goes to a temporary file in the target's
// folder (same file system, so the final rename is atomic) and is renamed over the target only once it is
// complete. A crash or an error never leaves a truncated image under the target name, and the temporary
// file is removed on failure.

#include "core/image/image.h"

#include <filesystem>
#include <string>
#include <vector>

namespace twinray {

// Any format OpenImageIO reads (.exr, .hdr, .png, ...), all channels, converted to linear-as-stored float
// (no colour conversion: an 8-bit PNG comes back as its code values / 255). Subimage 0, mip level 0.
Image read_image(const std::filesystem::path& path);

// 32-bit float OpenEXR (ZIP compressed, lossless: a float image reads back bit for bit).
// channel_names: one per channel; default R,G,B for 3, R,G,B,A for 4, Y for 1, else C0, C1, ...
void write_exr(const std::filesystem::path& path, const Image& image,
               const std::vector<std::string>& channel_names = {});

// 8-bit PNG, sRGB encoded: linear values are clamped to [0,1], passed through the sRGB OETF (IEC 61966-2-1,
// the piecewise curve, not a 2.2 gamma) and rounded to nearest; NaN writes as 0. Accepts 1 (grey),
// 2 (grey + alpha), 3 (RGB) or 4 (RGBA) channels; alpha is stored linearly (clamped and rounded only).
void write_png(const std::filesystem::path& path, const Image& image);

// The 8-bit sRGB code value for one linear value (the per-channel step of write_png; exposed for tests
// and for tools that print colours).
unsigned char linear_to_srgb8(float linear);

}  // namespace twinray
