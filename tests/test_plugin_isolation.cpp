// The isolated plugin backend (plugin:PATH, backends/plugin/isolated_plugin_backend.h): every way a plugin can
// fail (crash, abort, exit, exception, hang, runaway allocation, forbidden system call, bad hit) becomes a
// PluginFailure that names the stage and the exact ray, twinray carries on, and a fresh instance works again.
// The misbehaving plugins are tests/plugins/hostile_plugin.c (one build per behaviour) and throwing_plugin.cpp.

#include "backends/plugin/isolated_plugin_backend.h"
#include "backends/plugin/plugin_backend.h"
#include "backends/plugin/sanitizer_build.h"
#include "backends/registry.h"
#include "cli_runner.h"
#include "core/sampling/rng.h"
#include "core/util/input_error.h"
#include "plugin_failure_test_util.h"
#include "ray_test_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <thread>
#include <vector>

namespace twinray {
namespace {

using test::failure_of;
using test::make_ray;
using test::same_bits;
using test::same_hit_bits;

const std::filesystem::path kIsoBrute = TWINRAY_TEST_BRUTE_PLUGIN;

// Short limits keep the suite fast: the hanging plugin costs half a second per test, not ten.
PluginLimits quick_limits() {
  PluginLimits limits;
  limits.query_seconds = 0.5;
  limits.build_seconds = 30.0;
  return limits;
}

// 512 MiB: the worker's runtime, its 16 thread stacks (128 MiB of address space) and its malloc arenas fit;
// an unbounded allocation reaches the limit within a second or two of page faults, so the per-call limit is
// raised to keep the out-of-memory from being reported as a timeout on a busy machine.
PluginLimits small_memory_limits() {
  PluginLimits limits = quick_limits();
  limits.memory_bytes = std::size_t{512} << 20;
  limits.query_seconds = 30.0;
  return limits;
}

// A 4x4 grid of triangles in z = 0 (geom_id 0), a sphere above it (geom_id 1) and a second mesh of random
// triangles (geom_id 2).
SceneGeometry isolation_scene() {
  SceneGeometry g;
  TriangleMesh grid;
  grid.geom_id = 0;
  for (int j = 0; j <= 4; ++j)
    for (int i = 0; i <= 4; ++i) grid.positions.emplace_back(static_cast<float>(i), static_cast<float>(j), 0.0f);
  for (unsigned j = 0; j < 4; ++j)
    for (unsigned i = 0; i < 4; ++i) {
      const unsigned v = j * 5 + i;
      grid.indices.emplace_back(v, v + 1, v + 6);
      grid.indices.emplace_back(v, v + 6, v + 5);
    }
  grid.positions.reserve(grid.positions.size() + 1);
  g.meshes.push_back(grid);
  Sphere s;
  s.geom_id = 1;
  s.center = {2.0f, 2.0f, 1.5f};
  s.radius = 0.6f;
  g.spheres.push_back(s);
  Rng rng(3, 7);
  TriangleMesh soup;
  soup.geom_id = 2;
  for (unsigned k = 0; k < 30; ++k) {
    const glm::vec3 c{rng.next_float() * 4.0f, rng.next_float() * 4.0f, 0.5f + rng.next_float() * 2.0f};
    for (int v = 0; v < 3; ++v)
      soup.positions.push_back(c + glm::vec3(rng.next_float() - 0.5f, rng.next_float() - 0.5f, rng.next_float() - 0.5f));
    soup.indices.emplace_back(3 * k, 3 * k + 1, 3 * k + 2);
  }
  soup.positions.reserve(soup.positions.size() + 1);
  g.meshes.push_back(soup);
  return g;
}

// Rays from above towards the scene; no direction component is exactly zero (the hostile plugins' trigger).
std::vector<Ray> isolation_rays(std::size_t n, std::uint64_t seed) {
  Rng rng(seed, 11);
  std::vector<Ray> rays;
  for (std::size_t k = 0; k < n; ++k) {
    const glm::vec3 org{rng.next_float() * 6.0f - 1.0f, rng.next_float() * 6.0f - 1.0f, 3.0f + rng.next_float() * 2.0f};
    const glm::vec3 target{rng.next_float() * 4.0f + 0.01f, rng.next_float() * 4.0f + 0.02f, rng.next_float() * 2.0f};
    glm::vec3 dir = target - org;
    for (int a = 0; a < 3; ++a)
      if (dir[a] == 0.0f) dir[a] = 0.25f;
    rays.push_back(make_ray(org, dir, 0.0f, k % 5 == 0 ? 1.0f + rng.next_float() * 4.0f : test::kInf));
  }
  return rays;
}

// The same rays with one trigger at `index`: its direction's y component is exactly zero.
std::vector<Ray> rays_with_trigger(std::size_t n, std::size_t index) {
  std::vector<Ray> rays = isolation_rays(n, 29);
  rays[index].dir.y = 0.0f;
  return rays;
}

bool same_ray_bits(const Ray& a, const Ray& b) {
  return same_bits(a.org.x, b.org.x) && same_bits(a.org.y, b.org.y) && same_bits(a.org.z, b.org.z) &&
         same_bits(a.dir.x, b.dir.x) && same_bits(a.dir.y, b.dir.y) && same_bits(a.dir.z, b.dir.z) &&
         same_bits(a.tmin, b.tmin) && same_bits(a.tmax, b.tmax);
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// ---- correct plugins through the worker ----------------------------------------------------------------------

// The worker calls the same plugin functions on the same bits as the in-process backend: every answer is
// bit-identical, single rays and batches, closest and any hit, and the traversal counters agree.
TEST(PluginIsolation, BrutePluginGivesBitIdenticalAnswersThroughTheWorker) {
  const SceneGeometry g = isolation_scene();
  const std::unique_ptr<Backend> local = load_plugin_backend(kIsoBrute);
  const std::unique_ptr<IsolatedPluginBackend> isolated = make_isolated_plugin_backend(kIsoBrute, quick_limits());
  local->build(g);
  isolated->build(g);
  EXPECT_EQ(isolated->name(), "plugin:brute-c");
  EXPECT_TRUE(isolated->traits().honours_ties);
  EXPECT_EQ(isolated->build_stats().memory_bytes, local->build_stats().memory_bytes);

  std::vector<Ray> rays = isolation_rays(5000, 17);
  rays[10] = make_ray({1, 1, 1}, {0, 0, 0});  // invalid: a miss that never reaches the plugin
  std::vector<Hit> local_hits(rays.size()), isolated_hits(rays.size());
  std::vector<std::uint8_t> local_occ(rays.size()), isolated_occ(rays.size());
  QueryStats local_stats, isolated_stats;
  local->intersect(rays, local_hits, &local_stats);
  isolated->intersect(rays, isolated_hits, &isolated_stats);
  local->occluded(rays, local_occ, &local_stats);
  isolated->occluded(rays, isolated_occ, &isolated_stats);
  std::size_t found = 0;
  for (std::size_t k = 0; k < rays.size(); ++k) {
    ASSERT_TRUE(same_hit_bits(local_hits[k], isolated_hits[k])) << k;
    ASSERT_EQ(local_occ[k], isolated_occ[k]) << k;
    Hit single;
    EXPECT_EQ(isolated->intersect(rays[k], single, &isolated_stats), local_hits[k].found()) << k;
    EXPECT_TRUE(same_hit_bits(single, local_hits[k])) << k;
    EXPECT_EQ(isolated->occluded(rays[k], &isolated_stats), local_occ[k] != 0) << k;
    found += local_hits[k].found() ? 1 : 0;
  }
  EXPECT_GT(found, rays.size() / 3);  // the comparison covers real hits, on meshes and on the sphere
  EXPECT_EQ(isolated_stats.queries, local_stats.queries + 2 * rays.size());
  // Single calls repeat the batches' work exactly once more.
  EXPECT_EQ(isolated_stats.primitives_tested, 2 * local_stats.primitives_tested);
}

// Many parent threads at once (more than the worker's 16 channels, so some wait for a free one) get exactly
// the answers of one thread in process.
TEST(PluginIsolation, ConcurrentCallersGetTheSameAnswersAsOneThreadInProcess) {
  const SceneGeometry g = isolation_scene();
  const std::unique_ptr<Backend> local = load_plugin_backend(kIsoBrute);
  const std::unique_ptr<Backend> isolated = make_backend("plugin:" + kIsoBrute.string());
  local->build(g);
  isolated->build(g);
  const std::vector<Ray> rays = isolation_rays(2400, 5);
  std::vector<Hit> expected(rays.size());
  std::vector<std::uint8_t> expected_occ(rays.size());
  local->intersect(rays, expected);
  local->occluded(rays, expected_occ);

  constexpr std::size_t kThreads = 24;
  std::vector<std::size_t> mismatches(kThreads, 0);
  std::vector<std::thread> threads;
  for (std::size_t t = 0; t < kThreads; ++t)
    threads.emplace_back([&, t] {
      for (std::size_t k = t; k < rays.size(); k += kThreads) {
        Hit h;
        isolated->intersect(rays[k], h);
        mismatches[t] += same_hit_bits(h, expected[k]) ? 0 : 1;
        mismatches[t] += isolated->occluded(rays[k]) == (expected_occ[k] != 0) ? 0 : 1;
      }
      // And a batch per thread, concurrently with the others' single rays.
      const std::size_t begin = t * 100;
      std::vector<Hit> hits(100);
      isolated->intersect(std::span<const Ray>(rays).subspan(begin, 100), hits);
      for (std::size_t k = 0; k < 100; ++k) mismatches[t] += same_hit_bits(hits[k], expected[begin + k]) ? 0 : 1;
    });
  for (std::thread& t : threads) t.join();
  for (std::size_t t = 0; t < kThreads; ++t) EXPECT_EQ(mismatches[t], 0u) << "thread " << t;
}

// What ordinary plugins do while building (threads, malloc, printing; in C++ also std::vector, new,
// std::thread, iostream) passes the sandbox, and what they print is kept.
TEST(PluginIsolation, OrdinaryPluginCodeRunsInTheSandbox) {
  const SceneGeometry g = isolation_scene();
  const auto c_plugin = make_isolated_plugin_backend(TWINRAY_TEST_HOSTILE_NORMAL_PLUGIN, quick_limits());
  c_plugin->build(g);
  EXPECT_TRUE(contains(c_plugin->captured_output(), "built with 4 threads, sums 499500 499500 499500 499500"))
      << c_plugin->captured_output();
  const auto cxx_plugin = make_isolated_plugin_backend(TWINRAY_TEST_THROWING_PLUGIN, quick_limits());
  cxx_plugin->build(g);
  // 0 + 1 + ... + 99999, summed by four std::threads.
  EXPECT_TRUE(contains(cxx_plugin->captured_output(), "built 2 meshes with 4 threads, sum 4999950000"))
      << cxx_plugin->captured_output();
  // Queries (the NORMAL plugin answers every ray, trigger rays included, with a miss).
  const std::vector<Ray> rays = rays_with_trigger(200, 7);
  std::vector<Hit> hits(rays.size());
  c_plugin->intersect(rays, hits);
  for (const Hit& h : hits) EXPECT_FALSE(h.found());
  EXPECT_TRUE(contains(c_plugin->sandbox_description(), "seccomp")) << c_plugin->sandbox_description();
}

// ---- failures at query time ----------------------------------------------------------------------------------

struct QueryFailureCase {
  const char* name;
  const char* plugin;
  PluginFailureKind kind;
  const char* cause;
  const char* signal;   // "" when the failure is not a signal
  const char* syscall;  // cause "sandbox" only
  int exit_code = 0;
  bool small_memory = false;
};

class QueryFailure : public ::testing::TestWithParam<QueryFailureCase> {};

void expect_failure(const PluginFailure& f, const QueryFailureCase& c, const char* stage) {
  EXPECT_EQ(f.kind, c.kind) << f.what();
  EXPECT_EQ(f.cause, c.cause) << f.what();
  EXPECT_EQ(f.signal_name, c.signal) << f.what();
  EXPECT_EQ(f.syscall, c.syscall) << f.what();
  EXPECT_EQ(f.exit_code, c.exit_code) << f.what();
  EXPECT_EQ(f.stage, stage) << f.what();
  EXPECT_TRUE(contains(f.what(), "plugin:")) << f.what();
}

// A batch of 50 rays whose ray 37 is the trigger: the failure names ray 37 and its exact bits, the next call
// says the worker is gone, and a fresh instance of the same plugin works again.
TEST_P(QueryFailure, IsReportedWithTheExactRayAndAFreshInstanceWorks) {
  const QueryFailureCase& c = GetParam();
  const PluginLimits limits = c.small_memory ? small_memory_limits() : quick_limits();
  const SceneGeometry g = isolation_scene();
  const std::vector<Ray> rays = rays_with_trigger(50, 37);
  {
    const auto plugin = make_isolated_plugin_backend(c.plugin, limits);
    plugin->build(g);
    std::vector<Hit> hits(rays.size());
    const std::optional<PluginFailure> f = failure_of([&] { plugin->intersect(rays, hits); });
    ASSERT_TRUE(f.has_value()) << c.name << " did not fail";
    expect_failure(*f, c, "intersect");
    ASSERT_TRUE(f->ray_index.has_value()) << f->what();
    EXPECT_EQ(*f->ray_index, 37u);
    ASSERT_TRUE(f->ray.has_value());
    EXPECT_TRUE(same_ray_bits(*f->ray, rays[37])) << f->what();
    EXPECT_TRUE(contains(f->what(), "ray 37")) << f->what();
    EXPECT_TRUE(plugin->failure().has_value());

    // The worker is gone: every further call says so, with the same cause.
    Hit h;
    const std::optional<PluginFailure> again = failure_of([&] { plugin->intersect(rays[0], h); });
    ASSERT_TRUE(again.has_value());
    EXPECT_EQ(again->cause, c.cause);
    EXPECT_TRUE(contains(again->what(), "earlier call")) << again->what();
  }
  // A new instance is a new worker: the rays before the trigger are answered.
  const auto fresh = make_isolated_plugin_backend(c.plugin, limits);
  fresh->build(g);
  std::vector<Hit> hits(37);
  EXPECT_NO_THROW(fresh->intersect(std::span<const Ray>(rays).first(37), hits));
}

// The same through a single-ray occluded call: stage "occluded", ray index 0 (closest-hit only for the bad
// hit, since an any-hit query reports no hit to check).
TEST_P(QueryFailure, IsReportedFromASingleRayCall) {
  const QueryFailureCase& c = GetParam();
  const PluginLimits limits = c.small_memory ? small_memory_limits() : quick_limits();
  const SceneGeometry g = isolation_scene();
  const std::vector<Ray> rays = rays_with_trigger(3, 1);
  const auto plugin = make_isolated_plugin_backend(c.plugin, limits);
  plugin->build(g);
  const bool closest = c.kind == PluginFailureKind::ContractViolation;
  Hit h;
  const std::optional<PluginFailure> f =
      failure_of([&] { closest ? plugin->intersect(rays[1], h) : plugin->occluded(rays[1]); });
  ASSERT_TRUE(f.has_value()) << c.name << " did not fail";
  expect_failure(*f, c, closest ? "intersect" : "occluded");
  ASSERT_TRUE(f->ray_index.has_value());
  EXPECT_EQ(*f->ray_index, 0u);
  ASSERT_TRUE(f->ray.has_value());
  EXPECT_TRUE(same_ray_bits(*f->ray, rays[1]));
}

const QueryFailureCase kQueryFailures[] = {
    {"segv", TWINRAY_TEST_HOSTILE_SEGV_PLUGIN, PluginFailureKind::Crash, "signal", "SIGSEGV", ""},
    {"abort", TWINRAY_TEST_HOSTILE_ABORT_PLUGIN, PluginFailureKind::Crash, "abort", "SIGABRT", ""},
    {"exit", TWINRAY_TEST_HOSTILE_EXIT_PLUGIN, PluginFailureKind::Crash, "exit", "", "", 3},
    {"loop", TWINRAY_TEST_HOSTILE_LOOP_PLUGIN, PluginFailureKind::Timeout, "timeout", "", ""},
    {"alloc", TWINRAY_TEST_HOSTILE_ALLOC_PLUGIN, PluginFailureKind::Crash, "out-of-memory", "SIGSEGV", "", 0, true},
    {"exception", TWINRAY_TEST_THROWING_PLUGIN, PluginFailureKind::Crash, "exception", "", ""},
    // Under AddressSanitizer `new` does not throw std::bad_alloc: ASan reports out-of-memory and aborts.
    {"bad_alloc", TWINRAY_TEST_THROWING_BAD_ALLOC_PLUGIN, PluginFailureKind::Crash, "out-of-memory",
     kAddressSanitizer ? "SIGABRT" : "", "", 0, true},
    {"bad_hit", TWINRAY_TEST_HOSTILE_BAD_HIT_PLUGIN, PluginFailureKind::ContractViolation, "bad-hit", "", ""},
    {"open_read", TWINRAY_TEST_HOSTILE_OPEN_READ_PLUGIN, PluginFailureKind::Crash, "sandbox", "SIGSYS", "openat"},
    {"open_write", TWINRAY_TEST_HOSTILE_OPEN_WRITE_PLUGIN, PluginFailureKind::Crash, "sandbox", "SIGSYS", "openat"},
    {"socket", TWINRAY_TEST_HOSTILE_SOCKET_PLUGIN, PluginFailureKind::Crash, "sandbox", "SIGSYS", "socket"},
    {"fork", TWINRAY_TEST_HOSTILE_FORK_PLUGIN, PluginFailureKind::Crash, "sandbox", "SIGSYS", "clone"},
    {"exec", TWINRAY_TEST_HOSTILE_EXEC_PLUGIN, PluginFailureKind::Crash, "sandbox", "SIGSYS", "execve"},
    // raise(SIGSTOP): a stopped worker is not a dead one; the per-call limit cuts it (SIGKILL ends a stopped
    // process) and it is a timeout, not a wait.
    {"stop", TWINRAY_TEST_HOSTILE_STOP_PLUGIN, PluginFailureKind::Timeout, "timeout", "", ""},
};

INSTANTIATE_TEST_SUITE_P(PluginIsolation, QueryFailure, ::testing::ValuesIn(kQueryFailures),
                         [](const ::testing::TestParamInfo<QueryFailureCase>& param) { return std::string(param.param.name); });

// The exception's own text reaches the report.
TEST(PluginIsolation, EscapingExceptionCarriesItsMessage) {
  const auto plugin = make_isolated_plugin_backend(TWINRAY_TEST_THROWING_PLUGIN, quick_limits());
  plugin->build(isolation_scene());
  const std::vector<Ray> rays = rays_with_trigger(2, 0);
  const std::optional<PluginFailure> f = failure_of([&] { plugin->occluded(rays[0]); });
  ASSERT_TRUE(f.has_value());
  EXPECT_TRUE(contains(f->what(), "zero direction component")) << f->what();
}

// What the plugin printed comes with the failure, cut to the limit: its beginning and its end.
TEST(PluginIsolation, CapturedOutputIsTruncatedToTheLimitAndAttached) {
  PluginLimits limits = quick_limits();
  limits.output_bytes = 8 * 1024;
  const auto plugin = make_isolated_plugin_backend(TWINRAY_TEST_HOSTILE_PRINT_PLUGIN, limits);
  plugin->build(isolation_scene());
  const std::vector<Ray> rays = rays_with_trigger(4, 2);
  const std::optional<PluginFailure> f = failure_of([&] { plugin->occluded(rays[2]); });
  ASSERT_TRUE(f.has_value());
  EXPECT_EQ(f->signal_name, "SIGSEGV");
  const std::string& out = f->output;
  // The plugin printed 2 x 2000 lines of 61 bytes; 8 KiB of them are kept, plus the marker line.
  EXPECT_LE(out.size(), limits.output_bytes + 64) << out.size();
  EXPECT_GE(out.size(), limits.output_bytes) << out.size();
  EXPECT_TRUE(contains(out, "line 0000 of the hostile plugin")) << out.substr(0, 200);
  EXPECT_TRUE(contains(out, "line 1999 of the hostile plugin, padded to fifty bytes\n")) << out.substr(out.size() - 200);
  EXPECT_TRUE(contains(out, "bytes of output dropped")) << out;
}

// A line printed just before a crash is not lost in a stdio buffer (the worker's stdout is line-buffered).
TEST(PluginIsolation, LastLinePrintedBeforeACrashIsKept) {
  const auto plugin = make_isolated_plugin_backend(TWINRAY_TEST_HOSTILE_SEGV_PLUGIN, quick_limits());
  plugin->build(isolation_scene());
  const std::vector<Ray> rays = rays_with_trigger(1, 0);
  const std::optional<PluginFailure> f = failure_of([&] { plugin->occluded(rays[0]); });
  ASSERT_TRUE(f.has_value());
  EXPECT_EQ(f->output, "about to trace a ray with a zero direction component\n");
}

// ---- failures while loading and building ---------------------------------------------------------------------

TEST(PluginIsolation, CrashInBuildIsReportedWithStageBuild) {
  const auto plugin = make_isolated_plugin_backend(TWINRAY_TEST_HOSTILE_BUILD_CRASH_PLUGIN, quick_limits());
  const std::optional<PluginFailure> f = failure_of([&] { plugin->build(isolation_scene()); });
  ASSERT_TRUE(f.has_value());
  EXPECT_EQ(f->kind, PluginFailureKind::Crash);
  EXPECT_EQ(f->cause, "signal");
  EXPECT_EQ(f->signal_name, "SIGSEGV");
  EXPECT_EQ(f->stage, "build");
  EXPECT_FALSE(f->ray.has_value());
}

// Closing every descriptor (as daemonising code does) takes the worker's lifeline and shared memory with it;
// the sandbox refuses those two, so the verdict is one deterministic sandbox failure naming close, not the
// worker ending at some later moment as if twinray had gone.
TEST(PluginIsolation, ClosingTheWorkersDescriptorsIsStoppedBySeccomp) {
  const auto plugin = make_isolated_plugin_backend(TWINRAY_TEST_HOSTILE_CLOSE_FDS_PLUGIN, quick_limits());
  const std::optional<PluginFailure> f = failure_of([&] { plugin->build(isolation_scene()); });
  ASSERT_TRUE(f.has_value());
  EXPECT_EQ(f->kind, PluginFailureKind::Crash);
  EXPECT_EQ(f->cause, "sandbox");
  EXPECT_EQ(f->syscall, "close");
  EXPECT_EQ(f->stage, "build");
}

// While loading and building, files may be read (the loader needs to), but not created: the first seccomp
// phase stops an open for writing whatever the path.
TEST(PluginIsolation, CreatingAFileInBuildIsStoppedBySeccomp) {
  const auto plugin = make_isolated_plugin_backend(TWINRAY_TEST_HOSTILE_BUILD_WRITE_PLUGIN, quick_limits());
  const std::optional<PluginFailure> f = failure_of([&] { plugin->build(isolation_scene()); });
  ASSERT_TRUE(f.has_value());
  EXPECT_EQ(f->cause, "sandbox");
  EXPECT_EQ(f->signal_name, "SIGSYS");
  EXPECT_EQ(f->syscall, "openat");
  EXPECT_EQ(f->stage, "build");
  EXPECT_FALSE(std::filesystem::exists("/tmp/twinray-hostile-build-write.txt"));
}

// Reading outside the library folders in build is refused by Landlock (the plugin sees EACCES, the call
// returns an error rather than ending the worker).
TEST(PluginIsolation, ReadingOutsideTheLibraryFoldersInBuildIsRefusedByLandlock) {
  const auto plugin = make_isolated_plugin_backend(TWINRAY_TEST_HOSTILE_BUILD_READ_PLUGIN, quick_limits());
  if (!contains(plugin->sandbox_description(), "Landlock ABI"))
    GTEST_SKIP() << "Landlock is not available on this kernel: " << plugin->sandbox_description();
  try {
    plugin->build(isolation_scene());
    FAIL() << "the build should have failed";
  } catch (const PluginFailure& f) {
    FAIL() << "not a crash: " << f.what();
  } catch (const std::runtime_error& e) {
    EXPECT_TRUE(contains(e.what(), "could not open /etc/passwd: Permission denied")) << e.what();
  }
}

// A crash or a hang in create() (stage "load") comes out of the constructor as a PluginFailure.
TEST(PluginIsolation, CrashOrHangInCreateIsReportedWithStageLoad) {
  const std::optional<PluginFailure> crash =
      failure_of([&] { make_isolated_plugin_backend(TWINRAY_TEST_HOSTILE_CREATE_CRASH_PLUGIN, quick_limits()); });
  ASSERT_TRUE(crash.has_value());
  EXPECT_EQ(crash->cause, "signal");
  EXPECT_EQ(crash->signal_name, "SIGSEGV");
  EXPECT_EQ(crash->stage, "load");
  EXPECT_TRUE(contains(crash->what(), "libtwinray_hostile_create_crash_plugin.so")) << crash->what();

  PluginLimits limits = quick_limits();
  limits.build_seconds = 0.5;
  const std::optional<PluginFailure> hang =
      failure_of([&] { make_isolated_plugin_backend(TWINRAY_TEST_HOSTILE_CREATE_LOOP_PLUGIN, limits); });
  ASSERT_TRUE(hang.has_value());
  EXPECT_EQ(hang->kind, PluginFailureKind::Timeout);
  EXPECT_EQ(hang->stage, "load");
}

// A crash in destroy() is reported by shutdown() (stage "destroy"); the destructor swallows it.
TEST(PluginIsolation, CrashInDestroyIsReportedByShutdown) {
  const auto plugin = make_isolated_plugin_backend(TWINRAY_TEST_HOSTILE_DESTROY_CRASH_PLUGIN, quick_limits());
  plugin->build(isolation_scene());
  const std::optional<PluginFailure> f = failure_of([&] { plugin->shutdown(); });
  ASSERT_TRUE(f.has_value());
  EXPECT_EQ(f->signal_name, "SIGSEGV");
  EXPECT_EQ(f->stage, "destroy");
}

// The end of an instance is the end of a program that used the plugin: destroy(), then the plugin's atexit
// handlers and static destructors. A crash or a hang there is reported by shutdown(), stage "destroy".
TEST(PluginIsolation, CrashOrHangInAnExitHandlerIsReportedByShutdown) {
  const auto crashing = make_isolated_plugin_backend(TWINRAY_TEST_HOSTILE_EXIT_HANDLER_CRASH_PLUGIN, quick_limits());
  crashing->build(isolation_scene());
  std::vector<Hit> hits(64);
  crashing->intersect(isolation_rays(64, 5), hits);  // it answers (every ray a miss)
  const std::optional<PluginFailure> crash = failure_of([&] { crashing->shutdown(); });
  ASSERT_TRUE(crash.has_value());
  EXPECT_EQ(crash->kind, PluginFailureKind::Crash) << crash->what();
  EXPECT_EQ(crash->signal_name, "SIGSEGV") << crash->what();
  EXPECT_EQ(crash->stage, "destroy") << crash->what();

  const auto hanging = make_isolated_plugin_backend(TWINRAY_TEST_HOSTILE_EXIT_HANDLER_HANG_PLUGIN, quick_limits());
  hanging->build(isolation_scene());
  const std::optional<PluginFailure> hang = failure_of([&] { hanging->shutdown(); });
  ASSERT_TRUE(hang.has_value());
  EXPECT_EQ(hang->kind, PluginFailureKind::Timeout) << hang->what();
  EXPECT_EQ(hang->stage, "destroy") << hang->what();
  EXPECT_TRUE(contains(hang->what(), "exit handlers")) << hang->what();
}

// A thread of the plugin that crashes between calls (after the last answer) ends the worker while no call of
// twinray's waits for it: no caller has heard of it, so shutdown() reports it; a clean plugin's does not.
TEST(PluginIsolation, CrashBetweenCallsIsReportedByShutdown) {
  const auto plugin = make_isolated_plugin_backend(TWINRAY_TEST_HOSTILE_LATE_THREAD_CRASH_PLUGIN, quick_limits());
  plugin->build(isolation_scene());  // starts the thread, which crashes 100 ms later
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (!plugin->failure() && std::chrono::steady_clock::now() < give_up)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  const std::optional<PluginFailure> f = failure_of([&] { plugin->shutdown(); });
  ASSERT_TRUE(f.has_value());
  EXPECT_EQ(f->kind, PluginFailureKind::Crash) << f->what();
  EXPECT_EQ(f->signal_name, "SIGSEGV") << f->what();
  EXPECT_TRUE(contains(f->what(), "no call was in progress")) << f->what();
  // Reported once: a second shutdown has nothing new to say.
  EXPECT_NO_THROW(plugin->shutdown());

  // A failure a call has already thrown is not reported again at the end.
  const auto looping = make_isolated_plugin_backend(TWINRAY_TEST_HOSTILE_SEGV_PLUGIN, quick_limits());
  looping->build(isolation_scene());
  EXPECT_TRUE(failure_of([&] { looping->occluded(rays_with_trigger(2, 1)[1]); }).has_value());
  EXPECT_NO_THROW(looping->shutdown());
}

// The index of the ray in flight is the worker's word, which plugin code can write. A plugin that hangs while
// moving that index forward looks like a run of slow rays, each under the limit; it is stopped as a corrupted
// answer as soon as the index passes the request's last ray (no worker writes that), rather than when the
// request's whole budget (rays x per-call limit) runs out, or, for 4096 rays, the deadline.
TEST(PluginIsolation, ForgedProgressPastTheLastRayIsACrashNotAWait) {
  for (const std::size_t rays_per_request : {std::size_t{1}, std::size_t{4}}) {
    const auto plugin = make_isolated_plugin_backend(TWINRAY_TEST_FORGING_PLUGIN, quick_limits());
    plugin->build(isolation_scene());
    plugin->set_deadline(std::chrono::steady_clock::now() + std::chrono::seconds(3));
    const std::vector<Ray> rays = isolation_rays(rays_per_request, 5);
    std::vector<Hit> hits(rays.size());
    const std::optional<PluginFailure> f = failure_of([&] { plugin->intersect(rays, hits); });
    ASSERT_TRUE(f.has_value());
    EXPECT_EQ(f->kind, PluginFailureKind::Crash) << f->what();
    EXPECT_EQ(f->cause, "corrupted") << f->what();
    EXPECT_TRUE(contains(f->what(), "index of the ray in flight")) << f->what();
  }
}

// Load errors keep the in-process loader's messages (they are produced by the same code, in the worker).
TEST(PluginIsolation, LoadErrorsAreInputErrorsWithTheInProcessMessages) {
  const auto expect_load_error = [](const std::filesystem::path& path, const std::string& expected) {
    try {
      make_isolated_plugin_backend(path, quick_limits());
      ADD_FAILURE() << "loading " << path << " should have failed";
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), path);
      EXPECT_TRUE(contains(e.message(), expected)) << e.what();
    }
  };
  expect_load_error("/nonexistent/libnothing.so", "plugin library not found");
  const std::filesystem::path text = std::filesystem::temp_directory_path() / "twinray_isolation_not_a_library.so";
  std::ofstream(text) << "this is not an ELF file\n";
  expect_load_error(text, "cannot load it as a shared library");
  std::filesystem::remove(text);
  expect_load_error(TWINRAY_TEST_NO_ENTRY_PLUGIN, "does not export twinray_plugin_entry");
  expect_load_error(TWINRAY_TEST_WRONG_ABI_PLUGIN, "plugin ABI version mismatch: the plugin was built for version 2");
}

// The plugin runs in the worker's process and can write over the shared memory twinray reads its answers
// from. What it writes there (a sequence number, a status, a count the worker never writes) ends the call at
// once as a crash with cause "corrupted", rather than being waited on until a time limit: with the default
// limits (300 s per build, 10 s per ray) a wait would make this test time out.
TEST(PluginIsolation, OverwrittenSharedMemoryIsACrashNotAWait) {
  const auto plugin = make_isolated_plugin_backend(TWINRAY_TEST_HOSTILE_SCRIBBLE_PLUGIN);
  const std::vector<Ray> rays = isolation_rays(4096, 5);
  std::vector<Hit> hits(rays.size());
  const std::optional<PluginFailure> f = failure_of([&] {
    plugin->build(isolation_scene());
    for (int round = 0; round < 100000; ++round) plugin->intersect(rays, hits);
  });
  ASSERT_TRUE(f.has_value());
  EXPECT_EQ(f->kind, PluginFailureKind::Crash) << f->what();
  EXPECT_EQ(f->cause, "corrupted") << f->what();
  EXPECT_TRUE(contains(f->what(), "an answer the worker cannot give")) << f->what();
}

// exit(0) is a clean status, but not a clean end: called in build it is a crash of the build, with its code.
TEST(PluginIsolation, ExitZeroInBuildIsACrash) {
  const auto plugin = make_isolated_plugin_backend(TWINRAY_TEST_HOSTILE_EXIT0_BUILD_PLUGIN, quick_limits());
  const std::optional<PluginFailure> f = failure_of([&] { plugin->build(isolation_scene()); });
  ASSERT_TRUE(f.has_value());
  EXPECT_EQ(f->kind, PluginFailureKind::Crash) << f->what();
  EXPECT_EQ(f->cause, "exit") << f->what();
  EXPECT_EQ(f->exit_code, 0) << f->what();
  EXPECT_EQ(f->stage, "build") << f->what();
}

// exit(0) from a thread of the plugin, 50 ms after build, while twinray's calls come and go: whether a call
// was in flight or not, it is reported (by the call, or by shutdown) as a crash with exit code 0.
TEST(PluginIsolation, ExitZeroFromAPluginThreadIsACrash) {
  const auto plugin = make_isolated_plugin_backend(TWINRAY_TEST_HOSTILE_THREAD_EXIT0_PLUGIN, quick_limits());
  plugin->build(isolation_scene());
  const std::vector<Ray> rays = isolation_rays(256, 7);
  std::vector<Hit> hits(rays.size());
  std::optional<PluginFailure> f;
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (!f && std::chrono::steady_clock::now() < give_up) {
    f = failure_of([&] { plugin->intersect(rays, hits); });
    if (!f) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  if (!f) f = failure_of([&] { plugin->shutdown(); });
  ASSERT_TRUE(f.has_value());
  EXPECT_EQ(f->kind, PluginFailureKind::Crash) << f->what();
  EXPECT_EQ(f->cause, "exit") << f->what();
  EXPECT_EQ(f->exit_code, 0) << f->what();
}

// A plugin that prints a line on every query (debug output left in) is answered as any other: its output goes
// into a pipe twinray drains, so 2 x 20,000 lines neither block the worker nor fail the calls.
TEST(PluginIsolation, PrintingOnEveryQueryIsNoFailure) {
  const auto plugin = make_isolated_plugin_backend(TWINRAY_TEST_HOSTILE_CHATTY_PLUGIN, quick_limits());
  plugin->build(isolation_scene());
  const std::vector<Ray> rays = isolation_rays(20000, 9);
  std::vector<Hit> hits(rays.size());
  std::vector<std::uint8_t> occluded(rays.size(), 1);
  EXPECT_NO_THROW(plugin->intersect(rays, hits));
  EXPECT_NO_THROW(plugin->occluded(rays, occluded));
  for (const Hit& h : hits) EXPECT_FALSE(h.found());
  EXPECT_EQ(std::count(occluded.begin(), occluded.end(), 0), static_cast<std::ptrdiff_t>(rays.size()));
  EXPECT_NO_THROW(plugin->shutdown());
}

// dup2() of the shared memory's descriptor onto stdout (allowed: only 3 and 4 as targets are refused) turns
// the plugin's printing into writes over the memory the worker answers through: a corrupted answer, a crash
// at once, not a wait.
TEST(PluginIsolation, StdoutOntoTheSharedMemoryIsACrashNotAWait) {
  const auto plugin = make_isolated_plugin_backend(TWINRAY_TEST_HOSTILE_STDOUT_TO_SHM_PLUGIN, quick_limits());
  const std::optional<PluginFailure> f = failure_of([&] { plugin->build(isolation_scene()); });
  ASSERT_TRUE(f.has_value());
  EXPECT_EQ(f->kind, PluginFailureKind::Crash) << f->what();
  EXPECT_EQ(f->cause, "corrupted") << f->what();
}

// ---- limits, shutdown, resources -----------------------------------------------------------------------------

// The instance's deadline ends a hanging call even when the per-call limit is far away.
TEST(PluginIsolation, DeadlineEndsAHangingCall) {
  PluginLimits limits = quick_limits();
  limits.query_seconds = 60.0;
  const auto plugin = make_isolated_plugin_backend(TWINRAY_TEST_HOSTILE_LOOP_PLUGIN, limits);
  plugin->build(isolation_scene());
  plugin->set_deadline(std::chrono::steady_clock::now() + std::chrono::milliseconds(300));
  const std::vector<Ray> rays = rays_with_trigger(2, 1);
  const std::optional<PluginFailure> f = failure_of([&] { plugin->occluded(rays[1]); });
  ASSERT_TRUE(f.has_value());
  EXPECT_EQ(f->kind, PluginFailureKind::Timeout);
  EXPECT_TRUE(contains(f->what(), "deadline")) << f->what();
}

TEST(PluginIsolation, ShutdownDestroysTheInstanceAndLaterCallsThrow) {
  const auto plugin = make_isolated_plugin_backend(kIsoBrute, quick_limits());
  plugin->build(isolation_scene());
  EXPECT_NO_THROW(plugin->shutdown());
  EXPECT_FALSE(plugin->failure().has_value());
  Hit h;
  EXPECT_THROW(plugin->intersect(isolation_rays(1, 3)[0], h), PluginFailure);
}

// A missing worker is a clear error, not a crash.
TEST(PluginIsolation, MissingWorkerIsAClearError) {
  const char* previous = std::getenv("TWINRAY_PLUGIN_WORKER");
  const std::string saved = previous != nullptr ? previous : "";
  setenv("TWINRAY_PLUGIN_WORKER", "/nonexistent/twinray-plugin-worker", 1);
  try {
    make_isolated_plugin_backend(kIsoBrute);
    ADD_FAILURE() << "should have failed";
  } catch (const std::runtime_error& e) {
    EXPECT_TRUE(contains(e.what(), "TWINRAY_PLUGIN_WORKER")) << e.what();
    EXPECT_TRUE(contains(e.what(), "/nonexistent/twinray-plugin-worker")) << e.what();
  }
  if (previous != nullptr) setenv("TWINRAY_PLUGIN_WORKER", saved.c_str(), 1);
  else unsetenv("TWINRAY_PLUGIN_WORKER");
}

std::size_t open_descriptors() {
  std::size_t n = 0;
  for ([[maybe_unused]] const auto& entry : std::filesystem::directory_iterator("/proc/self/fd")) ++n;
  return n;
}

// Children of this process that still exist (running or not yet reaped), from /proc.
std::size_t child_processes() {
  std::size_t n = 0;
  for (const auto& task : std::filesystem::directory_iterator("/proc/self/task")) {
    std::ifstream children(task.path() / "children");
    std::string pid;
    while (children >> pid) ++n;
  }
  return n;
}

// Workers that end well or badly leave no descriptor (memfd, pipes, pidfd) and no process (not even a zombie)
// behind.
TEST(PluginIsolation, InstancesLeaveNoDescriptorsBehind) {
  const SceneGeometry g = isolation_scene();
  { const auto warm_up = make_isolated_plugin_backend(kIsoBrute, quick_limits()); }
  const std::size_t before = open_descriptors();
  for (int k = 0; k < 3; ++k) {
    const auto good = make_isolated_plugin_backend(kIsoBrute, quick_limits());
    good->build(g);
    const auto bad = make_isolated_plugin_backend(TWINRAY_TEST_HOSTILE_SEGV_PLUGIN, quick_limits());
    bad->build(g);
    EXPECT_THROW(bad->occluded(rays_with_trigger(1, 0)[0]), PluginFailure);
  }
  EXPECT_EQ(open_descriptors(), before);
  EXPECT_EQ(child_processes(), 0u);
}

}  // namespace
}  // namespace twinray

// ---- the commands --------------------------------------------------------------------------------------------

namespace twinray::testing {
namespace {

const std::string kCrashAt100 = TWINRAY_TEST_HOSTILE_CRASH_AT_100_PLUGIN;

// crosscheck with a plugin that crashes on its 100th ray: exit code 1, a message naming the plugin, the
// signal and the exact ray (the first batch's ray 99), and no JSON left behind.
TEST(PluginIsolationCommands, CrosscheckReportsTheCrashAndExitsOne) {
  const auto dir = scratch_dir("isolation-crosscheck");
  const CommandResult r = run_twinray("crosscheck " + quoted(source_path("scenes/cornell-box.json")) +
                                      " --backends embree,plugin:" + kCrashAt100 + " --rays 500 --json " +
                                      quoted(dir / "cc.json"));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("SIGSEGV"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("in intersect, ray 99: org"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("exactly '"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("libtwinray_hostile_crash_at_100_plugin.so"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "cc.json"));
}

// render: non-zero exit and no image, not even a temporary file.
TEST(PluginIsolationCommands, RenderWithACrashingPluginLeavesNoImage) {
  const auto dir = scratch_dir("isolation-render");
  const CommandResult r = run_twinray("render " + quoted(source_path("scenes/cornell-box.json")) + " --backend plugin:" +
                                      kCrashAt100 + " --spp 1 -o " + quoted(dir / "out.exr"));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("SIGSEGV"), std::string::npos) << r.output;
  EXPECT_TRUE(std::filesystem::is_empty(dir)) << "render left files behind";
}

// stress: the crashing case fails with the crash in its figures, and the run goes on with the next case.
TEST(PluginIsolationCommands, StressMarksTheCrashingCaseFailedAndGoesOn) {
  const CommandResult r = run_twinray(std::string("stress --case axis-aligned-signed-zero --case invalid-rays "
                                                  "--effort 0.05 --backends plugin:") +
                                      TWINRAY_TEST_HOSTILE_SEGV_PLUGIN);
  EXPECT_EQ(r.exit_code, 1) << r.output;
  const std::size_t crash_line = r.output.find("axis-aligned-signed-zero");
  ASSERT_NE(crash_line, std::string::npos) << r.output;
  const std::string line = r.output.substr(crash_line, r.output.find('\n', crash_line) - crash_line);
  EXPECT_NE(line.find("SIGSEGV"), std::string::npos) << line;
  EXPECT_NE(r.output.find("invalid-rays"), std::string::npos) << r.output;  // the next case ran
  EXPECT_NE(r.output.find("verdict:"), std::string::npos) << r.output;
}

// crosscheck judges every backend's u, v and ng on their own (hit_attributes.h): swapped barycentrics or a
// flipped normal give identical hits (no genuine mismatch) and still fail the run; the built-in oracle has none.
TEST(PluginIsolationCommands, CrosscheckFailsWrongAttributes) {
  const auto dir = scratch_dir("isolation-crosscheck-attributes");
  for (const char* bug : {"swapped_uv", "flipped_normal"}) {
    const std::string plugin = "plugin:" + (std::filesystem::path(TWINRAY_TEST_PLUGIN_DIR) /
                                            (std::string("libtwinray_scotty_") + bug + "_plugin.so")).string();
    const CommandResult r = run_twinray("crosscheck " + quoted(source_path("scenes/cornell-box.json")) + " --backends brute," +
                                        plugin + " --kinds camera,diffuse --rays 2000 --json " + quoted(dir / "cc.json"));
    EXPECT_EQ(r.exit_code, 1) << bug << "\n" << r.output;
    EXPECT_NE(r.output.find("wrong attributes of " + plugin), std::string::npos) << r.output;
    std::ifstream in(dir / "cc.json");
    const nlohmann::json j = nlohmann::json::parse(in);
    EXPECT_EQ(j.at("genuine_mismatches").get<int>(), 0) << bug;
    EXPECT_GT(j.at("wrong_attributes").at(plugin).get<int>(), 0) << bug;
    EXPECT_EQ(j.at("wrong_attributes").at("brute").get<int>(), 0) << bug;
    EXPECT_GT(j.at("kinds").at("camera").at("backends").at(plugin).at("wrong_attributes").get<int>(), 0) << bug;
    EXPECT_EQ(j.at("verdict"), "fail") << bug;
  }
}

// A plugin whose build() declines the scene failed the check; the scene is not bad input: exit 1, one line
// naming the plugin, its message shown but not obeyed (no terminal escapes, no line breaks of its own).
TEST(PluginIsolationCommands, CrosscheckWithADecliningPluginExitsOneWithASafeMessage) {
  const auto dir = scratch_dir("isolation-crosscheck-declines");
  const CommandResult r = run_twinray("crosscheck " + quoted(source_path("scenes/cornell-box.json")) +
                                      " --backends brute,plugin:" + TWINRAY_TEST_HOSTILE_BUILD_ESCAPES_PLUGIN +
                                      " --rays 100 --json " + quoted(dir / "cc.json"));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("build failed: \\x1b[2J"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find('\x1b'), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("\xc2\x9b"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "cc.json"));
}

// info --build: a crash while building is a failed check (exit 1) naming the stage.
TEST(PluginIsolationCommands, InfoReportsACrashInBuild) {
  const CommandResult r = run_twinray("info " + quoted(source_path("scenes/cornell-box.json")) + " --build plugin:" +
                                      TWINRAY_TEST_HOSTILE_BUILD_CRASH_PLUGIN);
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("crashed with SIGSEGV in build"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace twinray::testing
