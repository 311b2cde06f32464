#include "harness/report/report_writer.h"

#include "backends/registry.h"
#include "harness/report/bench_results.h"
#include "harness/report/cost_heatmap.h"
#include "harness/report/false_colour.h"
#include "harness/report/gnuplot.h"
#include "harness/report/scaling.h"
#include "core/image/image_io.h"
#include "core/scene/scene_loader.h"
#include "core/util/atomic_file.h"
#include "core/util/fp_mode.h"
#include "core/util/input_error.h"

#include <OpenImageIO/oiioversion.h>
#include <embree3/rtcore_config.h>
#include <fmt/core.h>
#include <nlohmann/json.hpp>
#include <oneapi/tbb/version.h>
#include <sys/utsname.h>

#include <algorithm>
#include <fstream>
#include <map>
#include <set>

namespace twinray::report {

namespace {

namespace fs = std::filesystem;

const char* const kReference = "embree-fast";
const char* const kRayKinds[] = {"primary", "shadow", "diffuse"};

// The query a renderer makes for each kind: shadow rays are any-hit queries, the others closest-hit.
const char* natural_query(const std::string& kind) { return kind == "shadow" ? "any" : "closest"; }

std::string num(double v, int digits = 3) {
  if (v == 0.0) return "0";
  return fmt::format("{:.{}g}", v, digits);
}
std::string ratio(double v) { return v > 0.0 ? fmt::format("{:.2f}x", v) : "-"; }
std::string mib(double bytes) { return fmt::format("{:.1f}", bytes / (1024.0 * 1024.0)); }

bool plots_enabled() {
  static const bool ok = gnuplot_available();
  return ok;
}

// Draws when gnuplot is there; returns the figure or nothing.
std::vector<Figure> line_figure(const LinePlot& plot, const fs::path& out, const std::string& file,
                                const std::string& caption) {
  if (!plots_enabled()) return {};
  plot_lines(plot, out / file);
  return {{file, caption, true}};
}

std::vector<Figure> bar_figure(const BarChart& chart, const fs::path& out, const std::string& file,
                               const std::string& caption) {
  if (!plots_enabled() || chart.categories.empty()) return {};
  plot_bars(chart, out / file);
  return {{file, caption, true}};
}

// Scenes of the headline table: the shared meshes and the interior views of them when measured, else
// every scene.
std::vector<std::string> headline_scenes(const BenchResults& r) {
  std::vector<std::string> out;
  for (const std::string& s : r.scenes()) {
    const auto b = std::find_if(r.builds.begin(), r.builds.end(), [&](const BuildRow& row) { return row.scene == s; });
    if (b != r.builds.end() && (b->family == "mesh" || b->family == "view")) out.push_back(s);
  }
  return out.empty() ? r.scenes() : out;
}

std::vector<std::string> ordered_backends(const BenchResults& r) {
  std::vector<std::string> order = {"bvh8", "bvh", kReference, "embree", "brute"};
  std::vector<std::string> out;
  const std::vector<std::string> present = r.backends();
  for (const std::string& b : order)
    if (std::find(present.begin(), present.end(), b) != present.end()) out.push_back(b);
  for (const std::string& b : present)
    if (std::find(out.begin(), out.end(), b) == out.end()) out.push_back(b);
  return out;
}

int max_threads(const BenchResults& r) {
  int m = 1;
  for (const TraceRow& t : r.traces) m = std::max(m, t.threads);
  return m;
}

void add_headline(Document& doc, const BenchResults& r) {
  Section s{"Headline", {}};
  s.paragraph("Build time (all threads) and single-thread throughput in million rays per second, each with its "
              "speed relative to embree-fast on the same geometry and the same rays in the same run (>1x: faster). "
              "Primary and diffuse rays are closest-hit queries, shadow rays any-hit queries, as the renderer "
              "issues them.");
  Table t;
  t.header = {"scene", "triangles", "backend", "build ms", "vs ef", "primary Mrays/s", "vs ef", "shadow Mrays/s",
              "vs ef", "diffuse Mrays/s", "vs ef"};
  t.numeric = {false, true, false, true, true, true, true, true, true, true, true};
  for (const std::string& scene : headline_scenes(r))
    for (const std::string& backend : ordered_backends(r)) {
      const auto b = r.build(scene, backend);
      if (!b) continue;
      std::vector<std::string> row = {scene, num(b->triangles, 6), backend, num(b->build_ms), ratio(b->speed_vs_ref)};
      for (const char* kind : kRayKinds) {
        const auto tr = r.trace(scene, backend, kind, natural_query(kind), 1);
        row.push_back(tr ? num(tr->mrays_per_s) : "-");
        row.push_back(tr ? ratio(tr->speed_vs_ref) : "-");
      }
      t.rows.push_back(row);
    }
  s.table(t);
  doc.sections.push_back(std::move(s));
}

BarChart throughput_chart(const BenchResults& r, int threads) {
  BarChart c;
  c.title = fmt::format("Throughput by ray kind, {} thread{}", threads, threads == 1 ? "" : "s");
  c.ylabel = "million rays per second";
  const std::vector<std::string> backends = ordered_backends(r);
  for (const std::string& scene : headline_scenes(r))
    for (const char* kind : kRayKinds)
      if (r.trace(scene, backends.front(), kind, natural_query(kind), threads) ||
          r.trace(scene, kReference, kind, natural_query(kind), threads))
        c.categories.push_back(scene + " " + kind);
  for (const std::string& backend : backends) {
    std::vector<double> values;
    bool any = false;
    for (const std::string& cat : c.categories) {
      const std::string scene = cat.substr(0, cat.rfind(' '));
      const std::string kind = cat.substr(cat.rfind(' ') + 1);
      const auto tr = r.trace(scene, backend, kind, natural_query(kind), threads);
      values.push_back(tr ? tr->mrays_per_s : NAN);
      any = any || tr.has_value();
    }
    if (!any) continue;
    c.series_titles.push_back(backend);
    c.values.push_back(values);
  }
  return c;
}

void add_throughput(Document& doc, const BenchResults& r, const fs::path& out) {
  Section s{"Throughput by ray kind", {}};
  s.figures(bar_figure(throughput_chart(r, 1), out, "throughput_1thread.svg",
                       "Single-thread throughput (primary, diffuse: closest-hit; shadow: any-hit)."));
  const int all = max_threads(r);
  if (all > 1)
    s.figures(bar_figure(throughput_chart(r, all), out, "throughput_all_threads.svg",
                         fmt::format("Throughput on all {} threads.", all)));
  Table t;
  t.header = {"scene", "backend", "kind", "query", "threads", "Mrays/s", "vs embree-fast", "hit fraction"};
  for (const std::string& scene : headline_scenes(r))
    for (const std::string& backend : ordered_backends(r))
      for (const TraceRow& tr : r.traces)
        if (tr.scene == scene && tr.backend == backend)
          t.rows.push_back({scene, backend, tr.kind, tr.query, std::to_string(tr.threads), num(tr.mrays_per_s),
                            ratio(tr.speed_vs_ref), num(tr.hit_fraction)});
  t.numeric = {false, false, false, false, true, true, true, true};
  s.paragraph("Every closest-hit and any-hit measurement on the headline scenes:");
  s.table(t);
  doc.sections.push_back(std::move(s));
}

struct SeriesPoints {
  std::vector<double> n, v;
};

// family -> backend -> points, over the procedural scale series (not the meshes and views).
template <class Value>
std::map<std::string, std::map<std::string, SeriesPoints>> build_series(const BenchResults& r, Value value) {
  std::map<std::string, std::map<std::string, SeriesPoints>> out;
  for (const BuildRow& b : r.builds) {
    if (b.family.empty() || b.family == "mesh" || b.family == "view") continue;
    const double v = value(b);
    if (!(v > 0.0)) continue;
    SeriesPoints& p = out[b.family][b.backend];
    p.n.push_back(b.triangles);
    p.v.push_back(v);
  }
  return out;
}

template <class Value>
std::map<std::string, std::map<std::string, SeriesPoints>> trace_series(const BenchResults& r, const std::string& kind,
                                                                        const std::string& query, Value value) {
  std::map<std::string, std::map<std::string, SeriesPoints>> out;
  for (const TraceRow& t : r.traces) {
    if (t.family.empty() || t.family == "mesh" || t.family == "view" || t.kind != kind || t.query != query || t.threads != 1) continue;
    const double v = value(t);
    if (!(v > 0.0)) continue;
    SeriesPoints& p = out[t.family][t.backend];
    p.n.push_back(t.triangles);
    p.v.push_back(v);
  }
  return out;
}

LinePlot series_plot(const std::map<std::string, std::map<std::string, SeriesPoints>>& series,
                     const std::set<std::string>& backends, const std::string& title, const std::string& ylabel,
                     bool log_y) {
  LinePlot p;
  p.title = title;
  p.xlabel = "triangles N";
  p.ylabel = ylabel;
  p.log_x = true;
  p.log_y = log_y;
  for (const auto& [family, by_backend] : series)
    for (const auto& [backend, pts] : by_backend) {
      if (!backends.count(backend)) continue;
      PlotSeries s;
      s.title = backend + " " + family;
      s.x = pts.n;
      s.y = pts.v;
      s.dashed = backend != "bvh";
      p.series.push_back(std::move(s));
    }
  return p;
}

void add_scaling(Document& doc, const BenchResults& r, const fs::path& out) {
  const auto build_ms = build_series(r, [](const BuildRow& b) { return b.build_ms; });
  if (build_ms.empty()) return;
  Section s{"Scaling with scene size", {}};
  s.paragraph("The procedural scale series (sphere, random soup, terrain height field, hairball of long thin "
              "triangles) from 1k triangles up, in steps of 4x. Expected: build time ~ N log N, nodes visited per ray ~ "
              "log N, bytes per primitive flat. Solid lines: bvh; dashed: Embree.");
  const std::set<std::string> both = {"bvh", kReference};
  const auto bytes = build_series(r, [](const BuildRow& b) { return b.bytes_per_prim; });
  const auto nodes = trace_series(r, "diffuse", "closest", [](const TraceRow& t) { return t.has_cost ? t.nodes_per_ray : 0.0; });
  const auto prims = trace_series(r, "diffuse", "closest", [](const TraceRow& t) { return t.has_cost ? t.prims_per_ray : 0.0; });
  const auto rate = trace_series(r, "diffuse", "closest", [](const TraceRow& t) { return t.mrays_per_s; });
  std::vector<Figure> figs;
  for (auto f : line_figure(series_plot(build_ms, both, "Build time against N", "build time (ms)", true), out,
                            "scaling_build_time.svg", "Build time (all threads) against triangle count, log-log."))
    figs.push_back(f);
  for (auto f : line_figure(series_plot(nodes, {"bvh"}, "bvh nodes visited per diffuse ray against N", "nodes per ray", true),
                            out, "scaling_nodes_per_ray.svg", "bvh: mean nodes visited per diffuse (closest-hit) ray, log-log."))
    figs.push_back(f);
  for (auto f : line_figure(series_plot(prims, {"bvh"}, "bvh primitives tested per diffuse ray against N", "primitives per ray", true),
                            out, "scaling_prims_per_ray.svg", "bvh: mean primitives tested per diffuse ray, log-log."))
    figs.push_back(f);
  for (auto f : line_figure(series_plot(bytes, both, "Memory per primitive against N", "bytes per primitive", true), out,
                            "scaling_bytes_per_prim.svg", "Acceleration structure memory per primitive (Embree: device memory monitor)."))
    figs.push_back(f);
  for (auto f : line_figure(series_plot(rate, both, "Diffuse-ray throughput against N (1 thread)", "Mrays/s", true), out,
                            "scaling_throughput.svg", "Single-thread diffuse closest-hit throughput against N."))
    figs.push_back(f);
  s.figures(figs);

  std::vector<std::string> verdicts;
  for (const auto& [family, by_backend] : build_ms)
    for (const auto& [backend, pts] : by_backend)
      if (both.count(backend)) verdicts.push_back(check_n_log_n("build time", backend + " " + family, pts.n, pts.v).verdict);
  for (const auto& [family, by_backend] : nodes)
    for (const auto& [backend, pts] : by_backend)
      verdicts.push_back(check_log_n("nodes per diffuse ray", backend + " " + family, pts.n, pts.v).verdict);
  for (const auto& [family, by_backend] : bytes)
    for (const auto& [backend, pts] : by_backend)
      if (both.count(backend)) verdicts.push_back(check_flat("bytes per primitive", backend + " " + family, pts.n, pts.v).verdict);
  s.paragraph(fmt::format("Measured growth (least-squares exponents in log-log; departure when the exponent differs "
                          "from the model's by more than {:.2f}, or memory per primitive varies by more than {:.0f}%):",
                          kExponentTolerance, 100.0 * kFlatTolerance));
  s.bullets(verdicts);

  Table t;
  t.header = {"scene", "triangles", "build ms", "nodes", "leaves", "depth", "SAH cost", "bytes/prim", "MiB",
              "nodes/ray (mean)", "nodes/ray (p99)", "prims/ray (mean)", "prims/ray (p99)"};
  for (const BuildRow& b : r.builds) {
    if (b.backend != "bvh") continue;
    const auto tr = r.trace(b.scene, "bvh", "diffuse", "closest", 1);
    t.rows.push_back({b.scene, num(b.triangles, 7), num(b.build_ms), num(b.nodes, 7), num(b.leaves, 7), num(b.depth),
                      num(b.sah_cost), num(b.bytes_per_prim), mib(b.memory_bytes),
                      tr && tr->has_cost ? num(tr->nodes_per_ray) : "-", tr && tr->has_cost ? num(tr->nodes_p99) : "-",
                      tr && tr->has_cost ? num(tr->prims_per_ray) : "-", tr && tr->has_cost ? num(tr->prims_p99) : "-"});
  }
  s.paragraph("bvh tree statistics for every scene (per-ray figures: diffuse closest-hit rays):");
  s.table(t);
  doc.sections.push_back(std::move(s));
}

void add_build_table(Document& doc, const BenchResults& r) {
  Section s{"Build time and memory, every scene", {}};
  Table t;
  t.header = {"scene", "backend", "triangles", "build ms", "Mprims/s", "vs embree-fast", "memory MiB", "bytes/prim"};
  t.numeric = {false, false, true, true, true, true, true, true};
  for (const BuildRow& b : r.builds)
    t.rows.push_back({b.scene, b.backend, num(b.triangles, 7), num(b.build_ms), num(b.mprims_per_s),
                      ratio(b.speed_vs_ref), mib(b.memory_bytes), num(b.bytes_per_prim)});
  s.table(t);
  doc.sections.push_back(std::move(s));
}

void copy_into(const fs::path& from, const fs::path& to) {
  fs::create_directories(to.parent_path());
  fs::copy_file(from, to, fs::copy_options::overwrite_existing);
}

void add_converge(Document& doc, const fs::path& dir, std::size_t index, const fs::path& out) {
  const fs::path json_path = dir / "converge.json";
  std::ifstream in(json_path);
  if (!in) throw InputError(json_path, "", "cannot open (is this a `twinray converge` output folder?)");
  nlohmann::json j;
  try {
    in >> j;
  } catch (const nlohmann::json::exception& e) {
    throw InputError(json_path, "", std::string("invalid JSON: ") + e.what());
  }
  const std::string scene = j.value("scene", "?");
  const std::string sub = fmt::format("converge-{}", index);
  Section s{fmt::format("Convergence: {}", fs::path(scene).filename().string()), {}};
  const nlohmann::json& ref = j["reference"];
  s.paragraph(fmt::format(
      "Error against wall time for each backend and sampling strategy, at doubling sample counts up to a budget of "
      "{} s per series, on {} threads. Reference: {}{}. For unbiased Monte Carlo relMSE falls as 1/time: slope -1 "
      "in log-log. relMSE = mean((x - r)^2 / (r^2 + {})).",
      num(j.value("budget_seconds", 0.0)), j.value("threads", 0), ref.value("path", "?"),
      ref.value("spp", 0) > 0 ? fmt::format(" ({} spp, embree, cached)", ref.value("spp", 0)) : "",
      j.value("error_metric_epsilon", 0.0)));
  if (j.contains("plot") && j["plot"].is_string()) {
    const std::string plot = j["plot"].get<std::string>();
    if (fs::exists(dir / plot)) {
      copy_into(dir / plot, out / sub / plot);
      s.figures({{sub + "/" + plot, "relMSE against time, log-log; legend: fitted slope", true}});
    }
  }
  Table t;
  t.header = {"backend", "strategy", "points", "max spp", "time at max (s)", "relMSE at max", "RMSE", "MAE",
              "slope vs time", "slope vs spp"};
  t.numeric = {false, false, true, true, true, true, true, true, true, true};
  std::vector<Figure> thumbs;
  if (ref.contains("png") && fs::exists(dir / ref["png"].get<std::string>())) {
    copy_into(dir / ref["png"].get<std::string>(), out / sub / ref["png"].get<std::string>());
    thumbs.push_back({sub + "/" + ref["png"].get<std::string>(), "reference", false});
  }
  for (const auto& series : j["series"]) {
    const auto& pts = series["points"];
    if (pts.empty()) continue;
    const auto& last = pts.back();
    auto slope_of = [&](const char* key) {
      return series.contains(key) && series[key].is_object() ? fmt::format("{:.3f}", series[key].value("slope", 0.0)) : std::string("-");
    };
    t.rows.push_back({series.value("backend", "?"), series.value("strategy", "?"), std::to_string(pts.size()),
                      std::to_string(last.value("spp", 0)), num(last.value("seconds", 0.0)),
                      num(last.value("rel_mse", 0.0)), num(last.value("rmse", 0.0)), num(last.value("mae", 0.0)),
                      slope_of("fit_time"), slope_of("fit_spp")});
    const std::string label = series.value("backend", "?") + " " + series.value("strategy", "?");
    for (const char* key : {"render_png", "difference_png", "error_png"}) {
      const std::string rel = series["images"].value(key, "");
      if (rel.empty() || !fs::exists(dir / rel)) continue;
      copy_into(dir / rel, out / sub / rel);
      const char* what = std::string(key) == "render_png" ? "render" : std::string(key) == "difference_png"
                                                                         ? "|difference| x4"
                                                                         : "relative sq. error (log, 1e-4..1)";
      thumbs.push_back({sub + "/" + rel, fmt::format("{}: {} at {} spp", label, what, last.value("spp", 0)), false});
    }
  }
  s.table(t);
  s.figures(thumbs);
  doc.sections.push_back(std::move(s));
}

void add_heatmaps(Document& doc, const std::vector<fs::path>& scenes, const fs::path& out,
                  const std::function<void(const std::string&)>& log) {
  if (scenes.empty()) return;
  Section s{"Per-pixel traversal cost (bvh)", {}};
  s.paragraph("One closest-hit camera ray through each pixel centre, traced by the bvh backend; colour = nodes "
              "visited (linear from 0 to the image's 99th percentile, dark blue to pale yellow). Bright regions are "
              "where the tree does badly: silhouettes, grazing angles, overlapping boxes.");
  std::vector<Figure> figs;
  Table t;
  t.header = {"scene", "resolution", "mean nodes/ray", "p99 nodes/ray", "mean primitives/ray"};
  t.numeric = {false, false, true, true, true};
  for (const fs::path& scene_path : scenes) {
    log("heatmap " + scene_path.string());
    const Scene scene = load_scene(scene_path);
    std::unique_ptr<Backend> bvh = make_backend("bvh");
    {
      const ScopedFlushDenormals ftz;
      bvh->build(scene.geometry);
    }
    const CostImages cost = traversal_cost_images(scene, *bvh);
    ScalarRange range = percentile_range(cost.nodes, 0.0, 0.99, false);
    range.lo = 0.0;
    const std::string file = "heatmaps/" + scene_path.stem().string() + ".nodes.png";
    fs::create_directories(out / "heatmaps");
    write_png(out / file, false_colour(cost.nodes, range));
    figs.push_back({file, fmt::format("{}: nodes visited per pixel (0 to {:.0f})", scene_path.filename().string(), range.hi), false});
    t.rows.push_back({scene_path.filename().string(), fmt::format("{}x{}", cost.nodes.width, cost.nodes.height),
                      num(cost.mean_nodes), num(range.hi), num(cost.mean_primitives)});
  }
  s.table(t);
  s.figures(figs);
  doc.sections.push_back(std::move(s));
}

void add_machine(Document& doc, const BenchResults* r) {
  Section s{"Machine and software", {}};
  Table t;
  t.header = {"item", "value"};
  t.numeric = {false, false};
  utsname u{};
  if (uname(&u) == 0)
    t.rows.push_back({"system (report)", fmt::format("{} {} {}", u.sysname, u.release, u.machine)});
  t.rows.push_back({"compiler (report)", fmt::format("{}", __VERSION__)});
  t.rows.push_back({"Embree / oneTBB / OpenImageIO (report)",
                    fmt::format("{} / {} / {}", RTC_VERSION_STRING, TBB_VERSION_STRING, OIIO_VERSION_STRING)});
  t.rows.push_back({"gnuplot", plots_enabled() ? "available" : "not found: plots left out"});
  if (r)
    for (const auto& [key, value] : r->context) t.rows.push_back({"benchmark " + key, value});
  s.table(t);
  doc.sections.push_back(std::move(s));
}

}  // namespace

Document build_report(const ReportInputs& inputs, const std::function<void(const std::string&)>& log) {
  fs::create_directories(inputs.out);
  Document doc;
  doc.title = "twinray benchmarks";
  doc.subtitle = "Build and traversal cost of every backend against embree-fast, and render error against time.";
  std::optional<BenchResults> bench;
  if (!inputs.bench.empty()) {
    bench = load_bench_results(inputs.bench);
    log(fmt::format("bench {}: {} build rows, {} trace rows", inputs.bench.string(), bench->builds.size(),
                    bench->traces.size()));
    doc.subtitle += fmt::format(" Benchmarks: {} ({}).", inputs.bench.filename().string(),
                                bench->context.count("date") ? bench->context.at("date") : "undated");
    add_headline(doc, *bench);
    add_throughput(doc, *bench, inputs.out);
    add_scaling(doc, *bench, inputs.out);
    add_build_table(doc, *bench);
  }
  for (std::size_t i = 0; i < inputs.converge_dirs.size(); ++i) add_converge(doc, inputs.converge_dirs[i], i, inputs.out);
  add_heatmaps(doc, inputs.heatmap_scenes, inputs.out, log);
  Section how{"How to reproduce", {}};
  how.code("bash scripts/bench.sh   # set-up, Release build, benchmarks, converge on the Cornell box, this report");
  how.paragraph("See docs/benchmarks.md for the individual commands and what every figure means.");
  doc.sections.push_back(std::move(how));
  add_machine(doc, bench ? &*bench : nullptr);
  return doc;
}

Document write_report(const ReportInputs& inputs, const std::function<void(const std::string&)>& log) {
  Document doc = build_report(inputs, log);
  write_file_atomically(inputs.out / "report.html", to_html(doc));
  write_file_atomically(inputs.out / "report.md", to_markdown(doc));
  return doc;
}

}  // namespace twinray::report
