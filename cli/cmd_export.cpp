// twinray export: a scene in another renderer's format (Mitsuba 3). Contract in docs/cli.md, conventions in
// docs/mitsuba.md.

#include "cli/commands.h"
#include "core/scene/mitsuba_export.h"
#include "core/scene/scene_loader.h"

#include <fmt/core.h>

#include <memory>
#include <optional>

namespace twinray::cli {

namespace {

struct ExportOptions {
  std::string scene;
  std::string to;
  std::string out_dir;
  std::optional<int> spp;
  std::optional<int> rr_depth;
};

int run_export(const ExportOptions& opt) {
  if (opt.to != "mitsuba") return report_bad_input("export", "unknown format '" + opt.to + "' (expected mitsuba)");
  if (opt.spp && *opt.spp < 1) return report_bad_input("export", "--spp must be at least 1");
  if (opt.rr_depth && *opt.rr_depth < 1) return report_bad_input("export", "--rr-depth must be at least 1");
  Scene scene = load_scene(opt.scene);
  if (opt.spp) scene.render.spp = *opt.spp;
  MitsubaExportOptions mo;
  mo.rr_depth = opt.rr_depth;
  const std::filesystem::path xml = export_mitsuba_scene(scene, opt.out_dir, mo);
  fmt::print("wrote        {} ({} shapes, {} materials)\n", xml.string(), scene.shapes.size(), scene.materials.size());
  return kExitOk;
}

}  // namespace

void add_export_command(CLI::App& app, CommandRunner& run) {
  auto opt = std::make_shared<ExportOptions>();
  CLI::App* cmd = app.add_subcommand("export", "Write a scene in another renderer's format: Mitsuba 3 XML plus PLY meshes (docs/mitsuba.md)");
  cmd->add_option("scene", opt->scene, "Scene (.json, .xml) or bare mesh (.obj, .ply)")->required();
  cmd->add_option("--to", opt->to, "Format: mitsuba")->required();
  cmd->add_option("out_dir", opt->out_dir, "Output folder (scene.xml, meshes/, textures/)")->required();
  cmd->add_option("--spp", opt->spp, "Sample count written into the scene (default: the scene's render.spp)");
  cmd->add_option("--rr-depth", opt->rr_depth, "Russian roulette depth written into the integrator (default: the scene's)");
  cmd->callback([opt, &run] { run = [opt] { return run_export(*opt); }; });
}

}  // namespace twinray::cli
