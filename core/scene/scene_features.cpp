#include "core/scene/scene_features.h"

#include <fmt/core.h>

namespace twinray {

std::vector<Feature> scene_features(const Scene& scene) {
  const SceneGeometry& g = scene.geometry;
  std::vector<Feature> f;
  f.push_back(g.has_triangles()
                  ? Feature{"triangle geometry", true, fmt::format("{} triangles in {} meshes", g.triangle_count(), g.meshes.size())}
                  : Feature{"triangle geometry", false, "no triangles"});
  f.push_back(g.has_spheres() ? Feature{"sphere geometry", true, fmt::format("{} spheres", g.sphere_count())}
                              : Feature{"sphere geometry", false, "no spheres"});

  std::size_t emitters = 0;
  for (const ShapeInfo& s : scene.shapes) emitters += scene.materials[s.material].type == MaterialType::Emissive ? 1 : 0;
  f.push_back(emitters ? Feature{"area light sampling", true, fmt::format("{} emissive shapes", emitters)}
                       : Feature{"area light sampling", false, "no emitters"});

  switch (scene.environment.type) {
    case EnvironmentType::None:
      f.push_back({"environment light", false, "no environment"});
      f.push_back({"environment sampling tables", false, "no environment map"});
      break;
    case EnvironmentType::Constant:
      f.push_back({"environment light", true, "constant radiance"});
      f.push_back({"environment sampling tables", false, "constant environment: uniform sphere sampling is exact"});
      break;
    case EnvironmentType::Image:
      f.push_back({"environment light", true,
                   fmt::format("image {}{}", scene.environment.image.string(), scene.environment.pixels ? " (procedural)" : "")});
      f.push_back({"environment sampling tables", true, "piecewise-constant 2D distribution over the texels"});
      break;
  }

  auto uses = [&](MaterialType type) {
    for (const ShapeInfo& s : scene.shapes)
      if (scene.materials[s.material].type == type) return true;
    return false;
  };
  f.push_back(uses(MaterialType::Glass) ? Feature{"dielectric (glass) BSDF", true, "glass material in use"}
                                        : Feature{"dielectric (glass) BSDF", false, "no glass"});
  f.push_back(uses(MaterialType::Mirror) ? Feature{"mirror BSDF", true, "mirror material in use"}
                                         : Feature{"mirror BSDF", false, "no mirror"});
  const bool delta = uses(MaterialType::Glass) || uses(MaterialType::Mirror);
  if (!delta) f.push_back({"caustic light tracing", false, "no mirror or glass"});
  else if (!emitters) f.push_back({"caustic light tracing", false, "no area lights"});
  else f.push_back({"caustic light tracing", true, "light paths through mirror/glass connected to the camera (render --caustics)"});
  return f;
}

}  // namespace twinray
