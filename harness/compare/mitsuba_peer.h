#pragma once
// Mitsuba 3 as a peer renderer: a scene exported by core/scene/mitsuba_export.h, rendered by
// scripts/mitsuba_render.py inside the virtual environment scripts/setup-mitsuba.sh creates.
//
// Where things are found:
//  - the Python interpreter: $TWINRAY_MITSUBA_VENV/bin/python, else the cache folder's
//    mitsuba-venv/bin/python (the folder of harness/converge/reference_cache.h);
//  - the driver script: $TWINRAY_MITSUBA_DRIVER, else scripts/mitsuba_render.py of the source tree twinray
//    was built from.
// When either is missing, or the interpreter cannot import mitsuba, MitsubaUnavailable says so and names the
// script that installs it (commands exit with code 2).

#include "harness/compare/image_comparison.h"

#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace twinray::compare {

class MitsubaUnavailable : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct MitsubaInstall {
  std::filesystem::path python;
  std::filesystem::path driver;
};

// Throws MitsubaUnavailable with what is missing and how to install it.
MitsubaInstall find_mitsuba();
// The same without throwing: nullopt when unavailable, with the reason in `why` when given.
std::optional<MitsubaInstall> probe_mitsuba(std::string* why = nullptr);

struct MitsubaRenderRequest {
  std::filesystem::path scene_xml;
  std::filesystem::path out_exr;  // the mean image; the variance goes beside it as STEM.var.exr
  int spp = 64;                   // per batch
  int batches = 8;
  double time_seconds = 0.0;      // > 0: batches until this much render time (at least `batches`)
  std::uint64_t seed = 0;
  int threads = 0;                // 0 = all cores
  std::string variant = "auto";   // auto, llvm_ad_rgb, scalar_rgb
};

struct MitsubaRender {
  NoisyImage image;
  std::string variant;
  std::string version;
  int spp = 0;            // total over the batches
  int batches = 0;
  double seconds = 0.0;   // the timed renders only (no loading, no warm-up)
  double load_seconds = 0.0;
  double warmup_seconds = 0.0;
  std::vector<double> pass_seconds;
};

struct MitsubaSweepPoint {
  int spp = 0;
  double seconds = 0.0;  // this render alone (its kernel compiled beforehand, untimed)
  Image image;
};

struct MitsubaSweep {
  std::string variant;
  std::vector<MitsubaSweepPoint> points;
};

// Error-against-time points for `converge --peer mitsuba`: one render per sample count 1, 2, 4, ... until
// the next would take the total past `budget_seconds` (at least two points) or max_spp; images go to
// work_dir. Throws as render_with_mitsuba does.
MitsubaSweep sweep_with_mitsuba(const MitsubaInstall& install, const std::filesystem::path& scene_xml,
                                const std::filesystem::path& work_dir, double budget_seconds, int max_spp,
                                std::uint64_t seed, int threads, const std::string& variant = "auto");

// Runs the driver and reads its outputs. Throws MitsubaUnavailable when Mitsuba is not installed and
// std::runtime_error (with the driver's log path) when the render fails.
MitsubaRender render_with_mitsuba(const MitsubaInstall& install, const MitsubaRenderRequest& request);

}  // namespace twinray::compare
