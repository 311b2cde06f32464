// twinray report: benchmark results, convergence studies and traversal heatmaps as an HTML page and its
// Markdown twin. Contract in docs/cli.md.

#include "cli/commands.h"
#include "harness/report/report_writer.h"

#include <fmt/core.h>

#include <memory>

namespace twinray::cli {

namespace {

struct ReportCommandOptions {
  std::string bench;
  std::vector<std::string> converge;
  std::vector<std::string> heatmaps;
  std::string out = "report";
};

int run_report(const ReportCommandOptions& opt) {
  if (opt.bench.empty() && opt.converge.empty() && opt.heatmaps.empty()) {
    return report_bad_input("report", "nothing to report: give --bench, --converge or --heatmap");
  }
  report::ReportInputs in;
  in.bench = opt.bench;
  for (const std::string& d : opt.converge) in.converge_dirs.emplace_back(d);
  for (const std::string& s : opt.heatmaps) in.heatmap_scenes.emplace_back(s);
  in.out = opt.out;
  const report::Document doc = report::write_report(in, [](const std::string& line) {
    fmt::print("report       {}\n", line);
    std::fflush(stdout);
  });
  fmt::print("wrote        {} and {} ({} images)\n", (in.out / "report.html").string(), (in.out / "report.md").string(),
             report::referenced_images(doc).size());
  return kExitOk;
}

}  // namespace

void add_report_command(CLI::App& app, CommandRunner& run) {
  auto opt = std::make_shared<ReportCommandOptions>();
  CLI::App* cmd = app.add_subcommand("report", "HTML + Markdown report of benchmarks and convergence studies (docs/cli.md).");
  cmd->add_option("--bench", opt->bench, "Google Benchmark JSON written by twinray_bench");
  cmd->add_option("--converge", opt->converge, "Output folder of `twinray converge` (repeatable)");
  cmd->add_option("--heatmap", opt->heatmaps, "Scene for a per-pixel bvh traversal-cost heatmap (repeatable)");
  cmd->add_option("--out", opt->out, "Output folder")->capture_default_str();
  cmd->callback([opt, &run] { run = [opt] { return run_report(*opt); }; });
}

}  // namespace twinray::cli
