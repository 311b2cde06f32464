#pragma once
// A whole cross-check: load the scene, build every backend, trace each ray kind through all of them, compare
// every backend with the first (the baseline) and reach a verdict. The `twinray crosscheck` command only parses
// flags into CrosscheckSettings and prints or writes what this returns (docs/cli.md has the contract).

#include "harness/crosscheck/ray_kinds.h"

#include <nlohmann/json.hpp>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace twinray::crosscheck {

struct CrosscheckSettings {
  std::filesystem::path scene;
  std::vector<std::string> backends;  // at least two; the first is the baseline
  std::size_t rays_per_kind = 100000;
  std::vector<RayKind> kinds{std::begin(kAllRayKinds), std::end(kAllRayKinds)};
  std::uint64_t seed = 1;
  // Rule every disagreement against the exact backend (harness/arbiter/arbiter.h), at most
  // arbiter_max_rays rays per kind (the first disputed ones).
  bool arbitrate = true;
  std::size_t arbiter_max_rays = 100000;
  // Also fail the verdict when the arbiter rules any backend's answer wrong (e.g. a backend that claims to be
  // watertight missing a hit exactly at an edge, which the classifier alone calls "edge").
  bool strict = false;
};

struct CrosscheckReport {
  std::string text;       // the human-readable tables, verdict line included
  nlohmann::json json;    // the JSON document of docs/cli.md
  std::size_t genuine_mismatches = 0;
  // Closest hits whose u, v or ng break the conventions (hit_attributes.h), all backends: part of the verdict.
  std::size_t wrong_attributes = 0;
  std::size_t arbiter_wrong = 0;  // answers the arbiter ruled wrong, all backends (in the verdict only when strict)
  bool strict = false;
  bool passed() const { return genuine_mismatches == 0 && wrong_attributes == 0 && (!strict || arbiter_wrong == 0); }
};

// Throws InputError for a bad scene or plugin, std::invalid_argument for bad settings.
CrosscheckReport run_crosscheck(const CrosscheckSettings& settings);

}  // namespace twinray::crosscheck
