#pragma once
// Reference images for convergence studies, rendered once and cached on disk.
//
// The cache key is a 64-bit FNV-1a hash of everything that determines the reference's pixels: the loaded
// scene (camera, materials, shape-to-material map, every vertex, index and sphere, the environment and the
// bytes of its image file), the render settings (max depth, Russian roulette depth, seed), the reference
// spp and a version tag bumped whenever the renderer's output changes meaning. Hashing the loaded scene
// rather than the scene file means an edited mesh invalidates the cache even when the JSON is unchanged.
//
// Folder: $TWINRAY_CACHE_DIR if set, else $XDG_CACHE_HOME/twinray, else $HOME/.cache/twinray, else
// .twinray-cache in the working directory; references live in its subfolder references/ as KEY.exr with
// KEY.json (the settings, for humans). Deleting the folder is always safe.

#include "core/scene/scene.h"

#include <cstdint>
#include <filesystem>
#include <string>

namespace twinray::converge {

struct ReferenceSettings {
  int spp = 1024;
  int max_depth = -1;
  int rr_depth = 5;
  std::uint64_t seed = 0;
};

// Bump when a renderer change alters reference images for the same scene and settings.
// 2: the Sobol sampler; 3: rendered with bvh8 instead of Embree (robust), whose float test misses every hit
// far out in float's range (stress case extreme-scale) where bvh8's hit decisions are exact.
inline constexpr const char* kReferenceVersion = "twinray-reference-3";

// The backend a cached reference is rendered with: the exact-hit default (bit-identical to brute).
inline constexpr const char* kReferenceBackend = "bvh8";

std::uint64_t reference_key(const Scene& scene, const ReferenceSettings& settings);
std::string key_hex(std::uint64_t key);

std::filesystem::path cache_directory();
std::filesystem::path cached_reference_path(const Scene& scene, const ReferenceSettings& settings);

}  // namespace twinray::converge
