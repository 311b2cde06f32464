// twinray render: one image of a scene through any backend. Contract in docs/rendering.md.

#include "backends/registry.h"
#include "cli/commands.h"
#include "core/image/image_io.h"
#include "core/render/renderer.h"
#include "core/scene/scene_loader.h"
#include "core/util/atomic_file.h"
#include "core/util/fp_mode.h"

#include <fmt/core.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>
#include <tbb/global_control.h>

#include <filesystem>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>

namespace twinray::cli {

namespace {

struct RenderCommandOptions {
  std::string scene;
  std::string backend = "bvh8";  // the fastest backend bit-identical to brute
  std::string integrator = "path";
  std::string strategy = "mis";
  std::string env_sampling = "importance";
  std::string sampler = "sobol4d";
  std::string caustics = "auto";
  std::optional<int> spp;
  std::optional<double> time_seconds;
  std::optional<int> max_depth;
  std::optional<int> rr_depth;
  std::optional<std::uint32_t> splits;
  std::optional<std::uint32_t> light_connections;
  std::optional<std::uint64_t> seed;
  int threads = 0;
  std::string output;
  std::string png;
  std::string aux;
  std::string env;
  std::string json;
};

// "out.exr" + "normals" -> "out.normals.exr"
std::filesystem::path aux_path(const std::filesystem::path& base, const std::string& name) {
  std::filesystem::path p = base;
  p.replace_extension();
  return p.string() + "." + name + ".exr";
}

std::optional<AuxChannels> parse_aux(const std::string& list, std::string& error) {
  AuxChannels aux;
  std::stringstream ss(list);
  std::string item;
  while (std::getline(ss, item, ',')) {
    if (item.empty()) continue;
    if (item == "normals") aux.normals = true;
    else if (item == "albedo") aux.albedo = true;
    else if (item == "depth") aux.depth = true;
    else if (item == "cost") aux.cost = true;
    else {
      error = "unknown --aux channel '" + item + "' (choose from normals, albedo, depth, cost)";
      return std::nullopt;
    }
  }
  return aux;
}

glm::dvec3 image_mean(const Image& img) {
  glm::dvec3 sum(0.0);
  for (std::size_t i = 0; i < img.pixel_count(); ++i)
    for (int c = 0; c < 3; ++c) sum[c] += static_cast<double>(img.data[3 * i + static_cast<std::size_t>(c)]);
  return img.pixel_count() ? sum / static_cast<double>(img.pixel_count()) : sum;
}

int run_render(const RenderCommandOptions& opt) {
  RenderOptions ro;
  if (opt.integrator == "path") ro.integrator = IntegratorKind::Path;
  else if (opt.integrator == "direct") ro.integrator = IntegratorKind::Direct;
  else return report_bad_input("render", "unknown --integrator '" + opt.integrator + "' (choose from direct, path)");
  if (opt.strategy == "mis") ro.settings.strategy = SamplingStrategy::Mis;
  else if (opt.strategy == "bsdf") ro.settings.strategy = SamplingStrategy::Bsdf;
  else if (opt.strategy == "light") ro.settings.strategy = SamplingStrategy::Light;
  else return report_bad_input("render", "unknown --strategy '" + opt.strategy + "' (choose from mis, bsdf, light)");
  if (opt.env_sampling == "importance") ro.env_importance_sampling = true;
  else if (opt.env_sampling == "uniform") ro.env_importance_sampling = false;
  else return report_bad_input("render", "unknown --env-sampling '" + opt.env_sampling + "' (choose from importance, uniform)");
  if (const std::optional<SamplerKind> k = parse_sampler_kind(opt.sampler)) ro.sampler = *k;
  else return report_bad_input("render", "unknown --sampler '" + opt.sampler + "' (choose from sobol4d, sobol, independent)");
  if (const std::optional<CausticsMode> m = parse_caustics_mode(opt.caustics)) ro.caustics = *m;
  else return report_bad_input("render", "unknown --caustics '" + opt.caustics + "' (choose from auto, off)");
  if (opt.spp && opt.time_seconds) return report_bad_input("render", "--spp and --time are exclusive");
  if (opt.spp && *opt.spp < 1) return report_bad_input("render", "--spp must be at least 1");
  if (opt.time_seconds && !(*opt.time_seconds > 0.0)) return report_bad_input("render", "--time must be positive");
  if (opt.max_depth && (*opt.max_depth == 0 || *opt.max_depth < -1))
    return report_bad_input("render", "--max-depth must be -1 (unlimited) or at least 1");
  if (opt.rr_depth && *opt.rr_depth < 1) return report_bad_input("render", "--rr-depth must be at least 1");
  if (opt.splits && (*opt.splits < 1 || *opt.splits > kMaxSplits))
    return report_bad_input("render", "--splits must be between 1 and " + std::to_string(kMaxSplits));
  if (opt.light_connections && *opt.light_connections > kMaxLightConnections)
    return report_bad_input("render", "--light-connections must be between 0 and " + std::to_string(kMaxLightConnections));
  if (opt.threads < 0) return report_bad_input("render", "--threads must be positive (0 = all cores)");
  std::string aux_error;
  const std::optional<AuxChannels> aux = parse_aux(opt.aux, aux_error);
  if (!aux) return report_bad_input("render", aux_error);

  std::unique_ptr<Backend> backend;
  try {
    backend = make_backend(opt.backend);
  } catch (const std::invalid_argument& e) {
    return report_bad_input("render", e.what());
  }

  Scene scene = load_scene(opt.scene);
  if (!opt.env.empty()) {
    // --env replaces the map (relative to the working directory, as any command-line path), keeping the
    // scene's rotation and scale when it had a map.
    if (scene.environment.type != EnvironmentType::Image) {
      scene.environment.rotation_deg = 0.0f;
      scene.environment.scale = 1.0f;
    }
    scene.environment.type = EnvironmentType::Image;
    scene.environment.image = std::filesystem::absolute(opt.env);
    scene.environment.pixels.reset();
  }
  ro.spp = opt.spp.value_or(scene.render.spp);
  ro.time_budget_seconds = opt.time_seconds.value_or(0.0);
  ro.settings.max_depth = opt.max_depth.value_or(scene.render.max_depth);
  ro.settings.rr_depth = opt.rr_depth.value_or(scene.render.rr_depth);
  if (opt.splits) ro.settings.splits = *opt.splits;
  if (opt.light_connections) ro.settings.light_connections = *opt.light_connections;
  ro.seed = opt.seed.value_or(scene.render.seed);
  ro.aux = *aux;
  if (ro.spp < 1) return report_bad_input("render", "the scene's render.spp must be at least 1");

  std::filesystem::path exr_out = opt.output;
  if (exr_out.empty() && opt.png.empty()) exr_out = std::filesystem::path(opt.scene).stem().string() + ".exr";
  const std::filesystem::path aux_base = !exr_out.empty() ? exr_out : std::filesystem::path(opt.png);

  std::optional<tbb::global_control> thread_limit;
  if (opt.threads > 0) thread_limit.emplace(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(opt.threads));
  const std::size_t threads = tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism);

  const ScopedFlushDenormals ftz;
  backend->build(scene.geometry);
  const BuildStats build = backend->build_stats();
  const RenderSetup setup(scene, ro, backend->traits());  // reads the environment map: may throw InputError
  const RenderResult result = render(setup, *backend);
  const RenderStats& st = result.stats;
  const RenderFeatures& features = setup.features();

  const Image image = result.film.mean_image();
  // A render's files form one result: when a later one cannot be written, the earlier ones are removed on
  // the way out, so no partial set is left behind looking complete.
  struct OutputSet {
    std::vector<std::string> paths;
    bool complete = false;
    ~OutputSet() {
      std::error_code ec;
      if (!complete)
        for (const std::string& p : paths) std::filesystem::remove(p, ec);
    }
  } outputs;
  std::vector<std::string>& written = outputs.paths;
  if (!exr_out.empty()) {
    write_exr(exr_out, image);
    written.push_back(exr_out.string());
  }
  if (!opt.png.empty()) {
    write_png(opt.png, image);
    written.push_back(opt.png);
  }
  nlohmann::json j_outputs = {{"image", exr_out.empty() ? nlohmann::json(nullptr) : nlohmann::json(exr_out.string())},
                              {"png", opt.png.empty() ? nlohmann::json(nullptr) : nlohmann::json(opt.png)}};
  auto write_aux = [&](bool wanted, const char* name, const Image& img, std::vector<std::string> channels) {
    if (!wanted) return;
    const std::filesystem::path p = aux_path(aux_base, name);
    write_exr(p, img, channels);
    written.push_back(p.string());
    j_outputs[name] = p.string();
  };
  write_aux(ro.aux.normals, "normals", result.film.normals_image(), {"X", "Y", "Z"});
  write_aux(ro.aux.albedo, "albedo", result.film.albedo_image(), {"R", "G", "B"});
  write_aux(ro.aux.depth, "depth", result.film.depth_image(), {"Z"});
  write_aux(features.traversal_cost, "cost", result.film.cost_image(), {"nodes", "primitives", "rays"});

  const glm::dvec3 mean = image_mean(image);
  const std::string depth_text = ro.settings.max_depth < 0 ? "unlimited" : std::to_string(ro.settings.max_depth);
  fmt::print("scene        {}\n", scene.source.string());
  fmt::print("backend      {} (build {:.3f} s, {:.1f} MiB)\n", backend->name(), build.build_seconds,
             static_cast<double>(build.memory_bytes) / (1024.0 * 1024.0));
  fmt::print("integrator   {} (strategy {}, env sampling {}, max depth {}, rr depth {}, splits {}, light connections {})\n",
             to_string(ro.integrator), to_string(ro.settings.strategy), opt.env_sampling, depth_text,
             ro.settings.rr_depth, ro.settings.splits, ro.settings.light_connections);
  fmt::print("image        {}x{}, {} spp, seed {}, sampler {}, {} threads\n", image.width, image.height, st.spp, ro.seed,
             to_string(ro.sampler), threads);
  for (const FeatureNote& n : features.notes)
    fmt::print("feature      {}: {}\n", n.name, n.used ? "used" : "left out (" + n.reason + ")");
  fmt::print("time         {:.3f} s\n", st.seconds);
  fmt::print("samples/s    {:.4g}\n", st.samples_per_second());
  fmt::print("rays/s       {:.4g} ({} closest-hit, {} shadow)\n", st.rays_per_second(), st.closest_hit_rays,
             st.shadow_rays);
  fmt::print("NaN/Inf      {} samples (replaced by 0), {} negative (clamped to 0)\n", st.nonfinite_samples,
             st.negative_samples);
  if (features.caustic_light_tracing)
    fmt::print("caustics     {} light paths, {} camera connections splatted, {} NaN/Inf dropped\n", st.light_paths,
               st.splats, st.nonfinite_splats);
  fmt::print("mean         ({:.5f}, {:.5f}, {:.5f})\n", mean.x, mean.y, mean.z);
  if (features.traversal_cost && st.rays() > 0)
    fmt::print("traversal    {:.2f} nodes, {:.2f} primitives per ray\n",
               static_cast<double>(st.query.nodes_visited) / static_cast<double>(st.rays()),
               static_cast<double>(st.query.primitives_tested) / static_cast<double>(st.rays()));
  fmt::print("wrote        {}\n", fmt::join(written, ", "));

  if (!opt.json.empty()) {
    nlohmann::json j_features = nlohmann::json::array();
    for (const FeatureNote& n : features.notes)
      j_features.push_back({{"name", n.name}, {"used", n.used}, {"reason", n.reason}});
    nlohmann::json j = {
        {"scene", scene.source.string()},
        {"backend", std::string(backend->name())},
        {"integrator", std::string(to_string(ro.integrator))},
        {"strategy", std::string(to_string(ro.settings.strategy))},
        {"env_sampling", opt.env_sampling},
        {"max_depth", ro.settings.max_depth},
        {"rr_depth", ro.settings.rr_depth},
        {"splits", ro.settings.splits},
        {"light_connections", ro.settings.light_connections},
        {"width", image.width},
        {"height", image.height},
        {"spp", st.spp},
        {"seed", ro.seed},
        {"sampler", to_string(ro.sampler)},
        {"threads", threads},
        {"time_budget_seconds", ro.time_budget_seconds > 0.0 ? nlohmann::json(ro.time_budget_seconds) : nlohmann::json(nullptr)},
        {"build_seconds", build.build_seconds},
        {"render_seconds", st.seconds},
        {"samples", st.samples},
        {"closest_hit_rays", st.closest_hit_rays},
        {"shadow_rays", st.shadow_rays},
        {"rays", st.rays()},
        {"samples_per_second", st.samples_per_second()},
        {"rays_per_second", st.rays_per_second()},
        {"nonfinite_samples", st.nonfinite_samples},
        {"negative_samples", st.negative_samples},
        {"caustics", std::string(to_string(ro.caustics))},
        {"caustic_light_tracing", features.caustic_light_tracing},
        {"light_paths", st.light_paths},
        {"splats", st.splats},
        {"nonfinite_splats", st.nonfinite_splats},
        {"mean", {mean.x, mean.y, mean.z}},
        {"features", j_features},
        {"features_used", features.used()},
        {"features_left_out", features.left_out()},
        {"outputs", j_outputs},
    };
    if (features.traversal_cost)
      j["traversal"] = {{"nodes_visited", st.query.nodes_visited},
                        {"primitives_tested", st.query.primitives_tested},
                        {"queries", st.query.queries}};
    write_file_atomically(opt.json, j.dump(2) + "\n");
  }
  outputs.complete = true;
  return kExitOk;
}

}  // namespace

void add_render_command(CLI::App& app, CommandRunner& run) {
  auto opt = std::make_shared<RenderCommandOptions>();
  CLI::App* cmd = app.add_subcommand("render", "Render a scene to a linear EXR and/or an sRGB PNG (docs/rendering.md).");
  cmd->add_option("scene", opt->scene, "Scene (.json) or bare mesh (.obj, .ply)")->required();
  cmd->add_option("--backend", opt->backend, "Intersection backend (bvh8, bvh, embree, embree-fast, brute, exact, plugin:PATH)")
      ->capture_default_str();
  cmd->add_option("--integrator", opt->integrator, "direct or path")->capture_default_str();
  cmd->add_option("--strategy", opt->strategy, "mis (default), bsdf (BSDF sampling only), light (light sampling only)")
      ->capture_default_str();
  cmd->add_option("--env-sampling", opt->env_sampling, "Environment map sampling: importance or uniform")
      ->capture_default_str();
  cmd->add_option("--caustics", opt->caustics,
                  "auto: light-trace caustics seen on diffuse surfaces when the scene has mirror or glass and an "
                  "area light; off: path tracing alone (docs/rendering.md)")
      ->capture_default_str();
  cmd->add_option("--spp", opt->spp, "Samples per pixel (default: the scene's render.spp)");
  cmd->add_option("--time", opt->time_seconds, "Render passes of 1 spp until SECONDS have passed (instead of --spp)");
  cmd->add_option("--max-depth", opt->max_depth, "Path segments: 1 emitters only, 2 direct light, -1 unlimited "
                                                 "(default: the scene's render.max_depth)");
  cmd->add_option("--rr-depth", opt->rr_depth, "Russian roulette from this many segments on (default: the scene's render.rr_depth, 5)");
  cmd->add_option("--splits", opt->splits, "Path continuations from each non-delta first vertex, 1 to 16 "
                                           "(path integrator; default 4; docs/rendering.md#path-splitting)");
  cmd->add_option("--light-connections", opt->light_connections,
                  "Light subpaths per camera sample joined to its non-delta vertices up to 3 segments deep, 0 to 4, "
                  "MIS weighted with the path tracer (path integrator; default 1; docs/rendering.md#light-connections)");
  cmd->add_option("--seed", opt->seed, "Random seed (default: the scene's render.seed)");
  cmd->add_option("--sampler", opt->sampler, "Random numbers: sobol4d (Owen-scrambled Sobol, pairs of 2D draws as 4D points; default), "
                  "sobol (Owen-scrambled Sobol, every 2D draw on its own) or independent (PCG32)")
      ->capture_default_str();
  cmd->add_option("--threads", opt->threads, "Worker threads (0 = all cores)")->capture_default_str();
  cmd->add_option("-o,--output", opt->output, "Linear float EXR (default SCENE-STEM.exr when no --png is given)");
  cmd->add_option("--png", opt->png, "sRGB 8-bit PNG");
  cmd->add_option("--aux", opt->aux, "Auxiliary EXRs next to the output: normals,albedo,depth,cost");
  cmd->add_option("--env", opt->env, "Environment map replacing the scene's (path relative to the working directory)");
  cmd->add_option("--json", opt->json, "Write the summary figures as JSON to this file");
  cmd->callback([opt, &run] { run = [opt] { return run_render(*opt); }; });
}

}  // namespace twinray::cli
