#pragma once
// `twinray converge --peer mitsuba`: Mitsuba 3's error-against-time curve on the same plot as twinray's.
//
// The scene is exported (core/scene/mitsuba_export.h) and Mitsuba renders it at 1, 2, 4, ... spp within the
// same budget as one twinray series (harness/compare/mitsuba_peer.h, sweep mode); each image's error is
// measured against the study's reference exactly as twinray's are. Times are render times: Mitsuba compiles
// the kernel of each sample count in an untimed warm-up render first.

#include "harness/converge/convergence_study.h"

#include <filesystem>
#include <functional>
#include <string>

namespace twinray::converge {

// The series is labelled backend "mitsuba", strategy = the variant that ran (llvm_ad_rgb or scalar_rgb).
// Throws compare::MitsubaUnavailable when Mitsuba is not installed.
ConvergeSeries mitsuba_series(const Scene& scene, const Image& reference, const StudySettings& settings,
                              const std::filesystem::path& work_dir, int threads,
                              const std::function<void(const std::string&)>& log);

}  // namespace twinray::converge
