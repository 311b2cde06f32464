// twinray info: what a scene holds, what twinray builds for it and what it leaves out.

#include "backends/registry.h"
#include "cli/commands.h"
#include "core/scene/scene_features.h"
#include "core/scene/scene_loader.h"
#include "core/util/atomic_file.h"
#include "core/util/fp_mode.h"

#include <fmt/core.h>
#include <nlohmann/json.hpp>

#include <memory>
#include <stdexcept>

namespace twinray::cli {

namespace {

struct InfoOptions {
  std::string scene;
  std::string build;  // backends to build, comma-separated; empty = none
  std::string json;
};

std::string_view material_type_name(MaterialType t) {
  switch (t) {
    case MaterialType::Diffuse: return "diffuse";
    case MaterialType::Mirror: return "mirror";
    case MaterialType::Glass: return "glass";
    case MaterialType::Emissive: return "emissive";
  }
  return "?";
}

nlohmann::json vec_json(const glm::vec3& v) { return {v.x, v.y, v.z}; }

int run_info(const InfoOptions& opt) {
  std::vector<std::string> to_build;
  if (!opt.build.empty()) {
    try {
      to_build = parse_backend_list(opt.build);
    } catch (const std::invalid_argument& e) {
      return report_bad_input("info", e.what());
    }
  }
  const Scene scene = load_scene(opt.scene);
  const SceneGeometry& g = scene.geometry;
  const Bounds3 b = g.bounds();

  fmt::print("scene:        {}{}\n", scene.source.string(), scene.from_bare_mesh ? " (bare mesh in a default scene)" : "");
  for (const std::string& a : scene.additions) fmt::print("added:        {}\n", a);
  fmt::print("shapes:       {} ({} meshes, {} spheres)\n", scene.shapes.size(), g.meshes.size(), g.spheres.size());
  fmt::print("triangles:    {}\n", g.triangle_count());
  fmt::print("skipped:      {} degenerate triangles, {} with non-finite vertices\n", scene.report.degenerate_triangles,
             scene.report.nonfinite_triangles);
  fmt::print("triangulated: {} polygons\n", scene.report.polygons_triangulated);
  if (b.empty()) {
    fmt::print("bounds:       empty\n");
  } else {
    fmt::print("bounds:       ({:.6g}, {:.6g}, {:.6g}) .. ({:.6g}, {:.6g}, {:.6g}), diagonal {:.6g}\n", b.lo.x, b.lo.y,
               b.lo.z, b.hi.x, b.hi.y, b.hi.z, b.diagonal());
  }
  fmt::print("camera:       {}x{}, vertical fov {:.6g} deg\n", scene.camera.width, scene.camera.height,
             scene.camera.vfov_deg);
  fmt::print("materials:   ");
  for (const Material& m : scene.materials) fmt::print(" {} ({})", m.name, material_type_name(m.type));
  fmt::print("\nrender:       spp {}, max depth {}, seed {}\n", scene.render.spp, scene.render.max_depth, scene.render.seed);

  const std::vector<Feature> features = scene_features(scene);
  fmt::print("features:\n");
  nlohmann::json j_features = nlohmann::json::array();
  for (const Feature& f : features) {
    fmt::print("  {:<30} {:<9} {}\n", f.name, f.used ? "built" : "left out", f.detail);
    j_features.push_back({{"name", f.name}, {"built", f.used}, {"detail", f.detail}});
  }

  nlohmann::json j_backends = nlohmann::json::object();
  if (!to_build.empty()) {
    const ScopedFlushDenormals ftz;
    fmt::print("backends:\n");
    for (const std::string& name : to_build) {
      std::unique_ptr<Backend> backend = make_backend(name);
      backend->build(g);
      const BuildStats s = backend->build_stats();
      fmt::print("  {:<12} build {:.4f} s, {:.2f} MiB, triangles {}, spheres {}", name, s.build_seconds,
                 static_cast<double>(s.memory_bytes) / (1024.0 * 1024.0), s.built_triangles ? "built" : "left out",
                 s.built_spheres ? "built" : "left out");
      if (s.nodes) fmt::print(", {} nodes, {} leaves, depth {}, SAH cost {:.4g}", s.nodes, s.leaves, s.max_depth, s.sah_cost);
      fmt::print("\n");
      j_backends[name] = {{"build_seconds", s.build_seconds}, {"memory_bytes", s.memory_bytes},
                          {"built_triangles", s.built_triangles}, {"built_spheres", s.built_spheres},
                          {"nodes", s.nodes}, {"leaves", s.leaves}, {"max_depth", s.max_depth}, {"sah_cost", s.sah_cost}};
    }
  }

  if (!opt.json.empty()) {
    nlohmann::json j = {{"scene", scene.source.string()},
                        {"from_bare_mesh", scene.from_bare_mesh},
                        {"additions", scene.additions},
                        {"shapes", scene.shapes.size()},
                        {"meshes", g.meshes.size()},
                        {"triangles", g.triangle_count()},
                        {"spheres", g.sphere_count()},
                        {"degenerate_triangles", scene.report.degenerate_triangles},
                        {"nonfinite_triangles", scene.report.nonfinite_triangles},
                        {"polygons_triangulated", scene.report.polygons_triangulated},
                        {"bounds", b.empty() ? nlohmann::json(nullptr)
                                             : nlohmann::json{{"min", vec_json(b.lo)}, {"max", vec_json(b.hi)}}},
                        {"features", j_features},
                        {"backends", j_backends}};
    write_file_atomically(opt.json, j.dump(2) + "\n");
  }
  return kExitOk;
}

}  // namespace

void add_info_command(CLI::App& app, CommandRunner& run) {
  auto opt = std::make_shared<InfoOptions>();
  CLI::App* cmd = app.add_subcommand("info", "Print a scene's counts, bounds and feature set (what is built, what is left out)");
  cmd->add_option("scene", opt->scene, "Scene (.json) or bare mesh (.obj, .ply)")->required();
  cmd->add_option("--build", opt->build, "Also build these backends (comma-separated) and print their build statistics");
  cmd->add_option("--json", opt->json, "Write the figures as JSON to this file");
  cmd->callback([opt, &run] { run = [opt] { return run_info(*opt); }; });
}

}  // namespace twinray::cli
