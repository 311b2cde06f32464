#include "core/image/image_io.h"

#include "core/util/input_error.h"

#include <OpenImageIO/imageio.h>
#include <fmt/core.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <string>
#include <system_error>

#include <unistd.h>

namespace twinray {
namespace fs = std::filesystem;

namespace {

// A temporary name next to the target: same folder (so rename() is atomic and never crosses file
// systems), hidden (leading dot), unique per process and call, and ending in the target's extension so
// the format plugin that OIIO picks by extension is the right one.
fs::path temporary_sibling(const fs::path& target) {
  static std::atomic<std::uint64_t> counter{0};
  // fmt rather than a chain of operator+: GCC 12 at -O3 warns falsely (-Wstringop-overflow, GCC bug
  // 105651) on "literal" + std::string.
  const std::string name = fmt::format(".{}.tmp{}-{}{}", target.filename().string(), ::getpid(),
                                       counter.fetch_add(1), target.extension().string());
  return target.parent_path() / name;
}

void check_writable_target(const fs::path& path, const Image& image) {
  if (image.width <= 0 || image.height <= 0)
    throw InputError(path, "", "refusing to write an empty image (" + std::to_string(image.width) + " x " +
                                   std::to_string(image.height) + ")");
  if (image.channels < 1) throw InputError(path, "", "refusing to write an image with no channels");
  if (image.data.size() != image.pixel_count() * static_cast<std::size_t>(image.channels))
    throw std::invalid_argument("write image: data size does not match width * height * channels");
  std::error_code ec;
  const fs::path folder = path.parent_path().empty() ? fs::path(".") : path.parent_path();
  if (!fs::is_directory(folder, ec)) throw InputError(path, "", "folder " + folder.string() + " does not exist");
  if (fs::is_directory(path, ec)) throw InputError(path, "", "is a directory");
}

// Writes `pixels` (already in `format`) through OIIO to a temporary file, then renames it over `path`.
void write_atomically(const fs::path& path, OIIO::ImageSpec spec, const void* pixels) {
  const fs::path tmp = temporary_sibling(path);
  std::string error;
  {
    std::unique_ptr<OIIO::ImageOutput> out = OIIO::ImageOutput::create(tmp.string());
    if (!out) {
      error = "no image writer for this format: " + OIIO::geterror();
    } else if (!out->open(tmp.string(), spec)) {
      error = "cannot open for writing: " + out->geterror();
    } else {
      if (!out->write_image(spec.format, pixels)) error = "write failed: " + out->geterror();
      if (!out->close() && error.empty()) error = "write failed on close: " + out->geterror();
    }
  }
  std::error_code ec;
  if (error.empty()) {
    fs::rename(tmp, path, ec);
    if (ec) error = "cannot move the finished image into place: " + ec.message();
  }
  if (!error.empty()) {
    fs::remove(tmp, ec);
    throw InputError(path, "", error);
  }
}

}  // namespace

Image read_image(const fs::path& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError(path, "", "file not found");
  if (fs::is_directory(path, ec)) throw InputError(path, "", "is a directory, not an image");
  std::unique_ptr<OIIO::ImageInput> in = OIIO::ImageInput::open(path.string());
  if (!in) throw InputError(path, "", "cannot read as an image: " + OIIO::geterror());
  const OIIO::ImageSpec& spec = in->spec();
  if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0)
    throw InputError(path, "", "image has zero size (" + std::to_string(spec.width) + " x " +
                                   std::to_string(spec.height) + " x " + std::to_string(spec.nchannels) + ")");
  Image image(spec.width, spec.height, spec.nchannels);
  if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, image.data.data()))
    throw InputError(path, "", "cannot read pixels: " + in->geterror());
  in->close();
  return image;
}

void write_exr(const fs::path& path, const Image& image, const std::vector<std::string>& channel_names) {
  check_writable_target(path, image);
  OIIO::ImageSpec spec(image.width, image.height, image.channels, OIIO::TypeDesc::FLOAT);
  if (!channel_names.empty()) {
    if (channel_names.size() != static_cast<std::size_t>(image.channels))
      throw std::invalid_argument("write_exr: one channel name per channel required");
    spec.channelnames = channel_names;
  } else if (image.channels == 1) {
    spec.channelnames = {"Y"};
  } else if (image.channels > 4) {
    spec.channelnames.clear();
    for (int c = 0; c < image.channels; ++c) spec.channelnames.push_back(fmt::format("C{}", c));
  }  // 2..4 channels: OIIO's defaults R, G, B, A
  spec.attribute("compression", "zip");
  write_atomically(path, spec, image.data.data());
}

unsigned char linear_to_srgb8(float linear) {
  if (!(linear > 0.0f)) return 0;  // also NaN
  if (linear >= 1.0f) return 255;
  // Double: 0.5 encodes to 187.516 code values, close enough to a rounding boundary that float pow could
  // land on the wrong side.
  const double l = static_cast<double>(linear);
  const double encoded = l <= 0.0031308 ? 12.92 * l : 1.055 * std::pow(l, 1.0 / 2.4) - 0.055;
  return static_cast<unsigned char>(std::lround(std::clamp(encoded, 0.0, 1.0) * 255.0));
}

void write_png(const fs::path& path, const Image& image) {
  check_writable_target(path, image);
  if (image.channels > 4)
    throw InputError(path, "", "PNG holds at most 4 channels, image has " + std::to_string(image.channels));
  const bool has_alpha = image.channels == 2 || image.channels == 4;
  const int colour_channels = has_alpha ? image.channels - 1 : image.channels;
  std::vector<unsigned char> bytes(image.data.size());
  for (std::size_t i = 0; i < bytes.size(); ++i) {
    const int c = static_cast<int>(i % static_cast<std::size_t>(image.channels));
    const float v = image.data[i];
    if (c < colour_channels) {
      bytes[i] = linear_to_srgb8(v);
    } else {
      bytes[i] = v > 0.0f ? static_cast<unsigned char>(std::lround(std::min(v, 1.0f) * 255.0f)) : 0;
    }
  }
  OIIO::ImageSpec spec(image.width, image.height, image.channels, OIIO::TypeDesc::UINT8);
  if (image.channels <= 2) spec.channelnames = has_alpha ? std::vector<std::string>{"Y", "A"} : std::vector<std::string>{"Y"};
  if (has_alpha) {
    spec.alpha_channel = image.channels - 1;
    // Our colour values are not premultiplied; without this OIIO would divide them by alpha.
    spec.attribute("oiio:UnassociatedAlpha", 1);
  }
  spec.attribute("oiio:ColorSpace", "sRGB");
  write_atomically(path, spec, bytes.data());
}

}  // namespace twinray
