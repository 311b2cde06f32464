#include "harness/compare/mitsuba_peer.h"

#include "harness/converge/reference_cache.h"
#include "core/image/image_io.h"

#include <fmt/core.h>
#include <nlohmann/json.hpp>

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <fstream>
#include <sstream>

extern char** environ;

namespace twinray::compare {

namespace {

constexpr const char* kInstallHint = "install it with: bash scripts/setup-mitsuba.sh (docs/mitsuba.md)";

std::filesystem::path default_python() {
  if (const char* venv = std::getenv("TWINRAY_MITSUBA_VENV"); venv != nullptr && *venv != '\0')
    return std::filesystem::path(venv) / "bin" / "python";
  return converge::cache_directory() / "mitsuba-venv" / "bin" / "python";
}

std::filesystem::path default_driver() {
  if (const char* d = std::getenv("TWINRAY_MITSUBA_DRIVER"); d != nullptr && *d != '\0') return d;
  return std::filesystem::path(TWINRAY_SOURCE_DIR) / "scripts" / "mitsuba_render.py";
}

// Runs argv with stdout and stderr appended to `log`; returns the exit status (-1 when it could not start).
int run_process(const std::vector<std::string>& args, const std::filesystem::path& log) {
  std::vector<char*> argv;
  for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, log.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) return -1;
  int status = 0;
  while (waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) return -1;
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
}

std::string tail_of(const std::filesystem::path& log, std::size_t max_chars = 2000) {
  std::ifstream in(log);
  std::stringstream ss;
  ss << in.rdbuf();
  std::string s = ss.str();
  if (s.size() > max_chars) s = "..." + s.substr(s.size() - max_chars);
  return s;
}

Image rgb(const Image& img) {
  if (img.channels == 3) return img;
  Image out(img.width, img.height, 3);
  for (std::size_t i = 0; i < img.pixel_count(); ++i)
    for (std::size_t c = 0; c < 3; ++c)
      out.data[3 * i + c] = img.data[i * static_cast<std::size_t>(img.channels) +
                                     std::min<std::size_t>(c, static_cast<std::size_t>(img.channels) - 1)];
  return out;
}

}  // namespace

std::optional<MitsubaInstall> probe_mitsuba(std::string* why) {
  MitsubaInstall install{default_python(), default_driver()};
  auto fail = [&](const std::string& reason) -> std::optional<MitsubaInstall> {
    if (why) *why = reason;
    return std::nullopt;
  };
  if (::access(install.python.c_str(), X_OK) != 0)
    return fail(fmt::format("Mitsuba 3 is not installed (no Python environment at {}); {}",
                            install.python.parent_path().parent_path().string(), kInstallHint));
  if (!std::filesystem::is_regular_file(install.driver))
    return fail(fmt::format("the Mitsuba driver script {} is missing (set TWINRAY_MITSUBA_DRIVER)", install.driver.string()));
  const std::filesystem::path log = std::filesystem::temp_directory_path() / fmt::format("twinray-mitsuba-probe-{}.log", ::getpid());
  const int rc = run_process({install.python.string(), "-c", "import mitsuba, drjit"}, log);
  const std::string output = tail_of(log, 400);
  std::filesystem::remove(log);
  if (rc != 0)
    return fail(fmt::format("the Python environment {} cannot import mitsuba ({}); {}",
                            install.python.parent_path().parent_path().string(), output, kInstallHint));
  return install;
}

MitsubaInstall find_mitsuba() {
  std::string why;
  if (std::optional<MitsubaInstall> install = probe_mitsuba(&why)) return *install;
  throw MitsubaUnavailable(why);
}

MitsubaRender render_with_mitsuba(const MitsubaInstall& install, const MitsubaRenderRequest& request) {
  std::filesystem::path json = request.out_exr;
  json.replace_extension(".json");
  std::filesystem::path var = request.out_exr;
  var.replace_extension(".var.exr");
  std::filesystem::path log = request.out_exr;
  log.replace_extension(".log");
  std::filesystem::remove(log);
  std::vector<std::string> args = {install.python.string(), install.driver.string(), request.scene_xml.string(),
                                   "--out", request.out_exr.string(), "--json", json.string(),
                                   "--spp", std::to_string(request.spp), "--batches", std::to_string(request.batches),
                                   // Mitsuba's seed is 32-bit.
                                   "--seed", std::to_string(request.seed & 0x3fffffffu),
                                   "--threads", std::to_string(request.threads), "--variant", request.variant};
  if (request.time_seconds > 0.0) {
    args.push_back("--time");
    args.push_back(fmt::format("{}", request.time_seconds));
  }
  const int rc = run_process(args, log);
  if (rc != 0)
    throw std::runtime_error(fmt::format("Mitsuba failed (exit {}) on {}; its log {}:\n{}", rc,
                                         request.scene_xml.string(), log.string(), tail_of(log)));
  std::ifstream in(json);
  const nlohmann::json j = nlohmann::json::parse(in);
  MitsubaRender r;
  r.image.mean = rgb(read_image(request.out_exr));
  r.batches = j.at("batches").get<int>();
  r.image.variance_of_mean =
      r.batches >= 2 ? rgb(read_image(var)) : Image(r.image.mean.width, r.image.mean.height, 3);
  r.variant = j.at("variant").get<std::string>();
  r.version = j.at("mitsuba_version").get<std::string>();
  r.spp = j.at("spp").get<int>();
  r.seconds = j.at("seconds").get<double>();
  r.load_seconds = j.at("load_seconds").get<double>();
  r.warmup_seconds = j.at("warmup_seconds").get<double>();
  r.pass_seconds = j.at("pass_seconds").get<std::vector<double>>();
  return r;
}

MitsubaSweep sweep_with_mitsuba(const MitsubaInstall& install, const std::filesystem::path& scene_xml,
                                const std::filesystem::path& work_dir, double budget_seconds, int max_spp,
                                std::uint64_t seed, int threads, const std::string& variant) {
  std::filesystem::create_directories(work_dir);
  const std::filesystem::path json = work_dir / "sweep.json", log = work_dir / "sweep.log";
  std::filesystem::remove(log);
  const std::vector<std::string> args = {install.python.string(), install.driver.string(), scene_xml.string(),
                                         "--out", (work_dir / "mitsuba.exr").string(), "--json", json.string(),
                                         "--sweep", fmt::format("{}", budget_seconds), "--max-spp", std::to_string(max_spp),
                                         "--seed", std::to_string(seed & 0x3fffffffu), "--threads", std::to_string(threads),
                                         "--variant", variant};
  const int rc = run_process(args, log);
  if (rc != 0)
    throw std::runtime_error(fmt::format("Mitsuba failed (exit {}) on {}; its log {}:\n{}", rc, scene_xml.string(),
                                         log.string(), tail_of(log)));
  std::ifstream in(json);
  const nlohmann::json j = nlohmann::json::parse(in);
  MitsubaSweep s;
  s.variant = j.at("variant").get<std::string>();
  for (const nlohmann::json& p : j.at("points"))
    s.points.push_back({p.at("spp").get<int>(), p.at("seconds").get<double>(), rgb(read_image(p.at("image").get<std::string>()))});
  return s;
}

}  // namespace twinray::compare
