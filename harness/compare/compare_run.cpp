#include "harness/compare/compare_run.h"

#include "backends/registry.h"
#include "harness/report/false_colour.h"
#include "core/image/image_io.h"
#include "core/render/renderer.h"
#include "core/scene/mitsuba_export.h"
#include "core/util/atomic_file.h"
#include "core/util/fp_mode.h"
#include "core/util/input_error.h"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>

namespace twinray::compare {

namespace {

// Mitsuba's batches in --time mode: small enough that the time budget is met closely, large enough that
// its per-call overhead stays small.
constexpr int kPeerSppPerTimedBatch = 8;
// The peer renders with seeds far from twinray's: not needed for independence (different generators), but
// it keeps the seeds of the two distinguishable in logs.
constexpr std::uint64_t kPeerSeedOffset = 1000;
// Nearest-texel environment maps go to Mitsuba with each texel repeated 4 x 4 times (core/scene/
// mitsuba_export.h): its bilinear lookup then differs from twinray's only in bands a quarter texel wide.
// Bilinear maps go as they are: both renderers then look them up the same way.
constexpr int kCompareEnvUpsample = 4;

Image rgb_of(const Image& img) {
  if (img.channels == 3) return img;
  Image out(img.width, img.height, 3);
  for (std::size_t i = 0; i < img.pixel_count(); ++i)
    for (std::size_t c = 0; c < 3; ++c)
      out.data[3 * i + c] = img.data[i * static_cast<std::size_t>(img.channels) +
                                     std::min<std::size_t>(c, static_cast<std::size_t>(img.channels) - 1)];
  return out;
}

nlohmann::json array3(const std::array<double, 3>& a) { return {a[0], a[1], a[2]}; }

nlohmann::json renderer_json(const RendererResult& r) {
  nlohmann::json j = {{"variant", r.variant},
                      {"seconds", r.seconds},
                      {"spp", r.spp},
                      {"batches", r.batches},
                      {"means", array3(r.means.mean)},
                      {"mean_standard_errors", array3(r.means.standard_error)},
                      {"relmse", r.rel_mse},
                      {"relmse_from_noise", r.rel_mse_from_noise},
                      {"efficiency", r.seconds * r.rel_mse},
                      {"image", r.name + ".exr"},
                      {"png", r.name + ".png"}};
  for (const auto& [k, v] : r.extra.items()) j[k] = v;
  return j;
}

nlohmann::json region_json(const RegionDifference& r) {
  static constexpr const char* kChannel[3] = {"r", "g", "b"};
  return {{"x0", r.x0}, {"y0", r.y0}, {"x1", r.x1}, {"y1", r.y1}, {"channel", kChannel[r.channel]},
          {"difference", r.difference}, {"standard_error", r.standard_error},
          {"z", std::isfinite(r.z) ? nlohmann::json(r.z) : nlohmann::json(r.z > 0 ? 1e308 : -1e308)}};
}

}  // namespace

RendererResult render_twinray_batches(const Scene& scene, const CompareSettings& settings) {
  const int batches = std::max(1, settings.batches);
  const int total_spp = settings.spp > 0 ? settings.spp : scene.render.spp;
  const int spp = std::max(1, total_spp / batches);
  const ScopedFlushDenormals ftz;
  std::unique_ptr<Backend> backend = make_backend(settings.backend);
  backend->build(scene.geometry);

  RendererResult r;
  r.name = "twinray";
  const int w = scene.camera.width, h = scene.camera.height;
  std::vector<double> sum(static_cast<std::size_t>(w) * static_cast<std::size_t>(h) * 3, 0.0), sum_sq(sum.size(), 0.0);
  std::uint64_t nonfinite = 0;
  std::string sampler;
  for (int b = 0; b < batches; ++b) {
    RenderOptions ro;
    ro.integrator = IntegratorKind::Path;
    ro.settings.max_depth = scene.render.max_depth;
    ro.settings.rr_depth = settings.rr_depth;
    ro.caustics = settings.caustics;
    ro.settings.splits = settings.splits;
    ro.settings.light_connections = settings.light_connections;
    ro.spp = spp;
    ro.time_budget_seconds = settings.time_seconds > 0.0 ? settings.time_seconds / batches : 0.0;
    ro.seed = settings.seed + static_cast<std::uint64_t>(b);
    ro.show_progress = false;
    const RenderSetup setup(scene, ro, backend->traits());
    const RenderResult result = render(setup, *backend);
    r.seconds += result.stats.seconds;
    r.spp += result.stats.spp;
    nonfinite += result.stats.nonfinite_samples;
    const Image mean = result.film.mean_image();
    for (std::size_t i = 0; i < sum.size(); ++i) {
      const double v = mean.data[i];
      sum[i] += v;
      sum_sq[i] += v * v;
    }
  }
  // With --time the batches may differ in spp; they are still independent unbiased estimates, weighted
  // equally here as the variance estimate assumes.
  r.batches = batches;
  r.variant = settings.backend;
  r.image.mean = Image(w, h, 3);
  r.image.variance_of_mean = Image(w, h, 3);
  const double n = batches;
  for (std::size_t i = 0; i < sum.size(); ++i) {
    const double mean = sum[i] / n;
    r.image.mean.data[i] = static_cast<float>(mean);
    if (batches >= 2)
      r.image.variance_of_mean.data[i] = static_cast<float>(std::max(0.0, sum_sq[i] / n - mean * mean) / (n - 1.0));
  }
  r.means = channel_means(r.image);
  r.extra = {{"backend", settings.backend}, {"nonfinite_samples", nonfinite}, {"caustics", to_string(settings.caustics)},
             {"splits", settings.splits},
             {"light_connections", settings.light_connections}};
  return r;
}

CompareResult run_compare(const Scene& scene, const std::filesystem::path& scene_path, const CompareSettings& settings,
                          const std::function<void(const std::string&)>& log) {
  if (settings.peer != "mitsuba") throw std::invalid_argument("unknown peer '" + settings.peer + "' (expected mitsuba)");
  const MitsubaInstall install = find_mitsuba();  // before any work: a missing peer is an error at once

  CompareResult result;
  Image reference;
  if (!settings.reference.empty()) {
    reference = rgb_of(read_image(settings.reference));
    if (reference.width != scene.camera.width || reference.height != scene.camera.height)
      throw InputError(settings.reference, "",
                       fmt::format("reference is {}x{}, the scene renders {}x{}", reference.width, reference.height,
                                   scene.camera.width, scene.camera.height));
    result.has_reference = true;
  }
  std::filesystem::create_directories(settings.out / "mitsuba");

  const int batches = std::max(1, settings.batches);
  const int total_spp = settings.spp > 0 ? settings.spp : scene.render.spp;

  log(fmt::format("twinray      {} batches of {} spp, backend {}", batches, std::max(1, total_spp / batches), settings.backend));
  result.twinray = render_twinray_batches(scene, settings);

  Scene exported = scene;
  exported.render.spp = std::max(1, total_spp / batches);
  MitsubaExportOptions export_options;
  export_options.rr_depth = settings.rr_depth;
  export_options.env_upsample = kCompareEnvUpsample;
  const std::filesystem::path xml = export_mitsuba_scene(exported, settings.out / "mitsuba", export_options);
  MitsubaRenderRequest request;
  request.scene_xml = xml;
  request.out_exr = settings.out / "mitsuba.exr";
  request.spp = settings.time_seconds > 0.0 ? kPeerSppPerTimedBatch : std::max(1, total_spp / batches);
  request.batches = batches;
  request.time_seconds = settings.time_seconds;
  request.seed = settings.seed + kPeerSeedOffset;
  request.threads = settings.threads;
  request.variant = settings.mitsuba_variant;
  log(fmt::format("mitsuba      {} batches of {} spp{}", batches, request.spp,
                  settings.time_seconds > 0.0 ? fmt::format(" for {} s", settings.time_seconds) : std::string()));
  const MitsubaRender m = render_with_mitsuba(install, request);
  std::filesystem::rename(settings.out / "mitsuba.log", settings.out / "mitsuba" / "mitsuba.log");
  std::filesystem::rename(settings.out / "mitsuba.json", settings.out / "mitsuba" / "driver.json");
  std::filesystem::rename(settings.out / "mitsuba.var.exr", settings.out / "mitsuba" / "variance.exr");
  RendererResult& p = result.peer;
  p.name = "mitsuba";
  p.variant = m.variant;
  p.image = m.image;
  p.means = channel_means(p.image);
  p.seconds = m.seconds;
  p.spp = m.spp;
  p.batches = m.batches;
  p.extra = {{"version", m.version}, {"load_seconds", m.load_seconds}, {"warmup_seconds", m.warmup_seconds},
             {"pass_seconds", m.pass_seconds}};
  if (p.image.mean.width != scene.camera.width || p.image.mean.height != scene.camera.height)
    throw std::runtime_error("Mitsuba rendered an image of another size");

  result.comparison = compare_images(result.twinray.image, p.image);
  Image truth = reference;
  if (!result.has_reference) {
    truth = Image(scene.camera.width, scene.camera.height, 3);
    for (std::size_t i = 0; i < truth.data.size(); ++i)
      truth.data[i] = 0.5f * (result.twinray.image.mean.data[i] + p.image.mean.data[i]);
  }
  for (RendererResult* r : {&result.twinray, &p}) {
    r->rel_mse_from_noise = expected_rel_mse(r->image, truth);
    r->rel_mse = result.has_reference ? rel_mse(r->image.mean, reference) : r->rel_mse_from_noise;
  }

  const std::filesystem::path& out = settings.out;
  write_exr(out / "twinray.exr", result.twinray.image.mean);
  write_png(out / "twinray.png", result.twinray.image.mean);
  write_exr(out / "mitsuba.exr", p.image.mean);
  write_png(out / "mitsuba.png", p.image.mean);
  write_png(out / "difference.png",
            report::false_colour(pixel_z_image(result.twinray.image, p.image), {0.0, 4.0, false}));
  write_png(out / "regions.png",
            report::false_colour(region_z_image(result.comparison, scene.camera.width, scene.camera.height),
                                 {0.0, 2.0 * result.comparison.threshold, false}));
  result.json = compare_json(result, scene_path, settings);
  write_file_atomically(out / "compare.json", result.json.dump(2) + "\n");
  return result;
}

nlohmann::json compare_json(const CompareResult& r, const std::filesystem::path& scene_path,
                            const CompareSettings& settings) {
  const Comparison& c = r.comparison;
  nlohmann::json differing = nlohmann::json::array();
  for (const RegionDifference& d : c.differing) differing.push_back(region_json(d));
  const double tw_eff = r.twinray.seconds * r.twinray.rel_mse;
  const double peer_eff = r.peer.seconds * r.peer.rel_mse;
  return {
      {"scene", scene_path.string()},
      {"peer", settings.peer},
      {"verdict", c.agree ? "agree" : "differ"},
      {"threads", settings.threads},
      {"seed", settings.seed},
      {"time_budget_seconds", settings.time_seconds > 0.0 ? nlohmann::json(settings.time_seconds) : nlohmann::json(nullptr)},
      {"reference", r.has_reference ? nlohmann::json(settings.reference.string()) : nlohmann::json(nullptr)},
      {"relmse_kind", r.has_reference ? "reference" : "noise"},
      {"renderers", {{"twinray", renderer_json(r.twinray)}, {r.peer.name, renderer_json(r.peer)}}},
      // time x relMSE of twinray over the peer's: below 1, twinray is the more efficient.
      {"efficiency_ratio", peer_eff > 0.0 ? nlohmann::json(tw_eff / peer_eff) : nlohmann::json(nullptr)},
      {"comparison",
       {{"regions", static_cast<int>(c.regions.size())},
        {"grid", kRegionGrid},
        {"threshold", c.threshold},
        {"family_false_alarm", kFamilyFalseAlarm},
        {"max_abs_z", std::isfinite(c.max_abs_z) ? nlohmann::json(c.max_abs_z) : nlohmann::json(1e308)},
        {"differing_regions", differing},
        {"relmse_between", c.rel_mse_between},
        {"relmse_between_from_noise", c.rel_mse_between_noise},
        {"relmse_excess", c.rel_mse_excess()}}},
      {"images",
       {{"twinray", "twinray.exr"}, {"peer", "mitsuba.exr"}, {"difference_png", "difference.png"},
        {"regions_png", "regions.png"}, {"peer_scene", "mitsuba/scene.xml"}}},
  };
}

}  // namespace twinray::compare
