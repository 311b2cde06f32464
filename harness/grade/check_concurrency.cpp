// thread-safety: the same rays answered by many threads at once on the same instance (each thread all rays,
// starting at a different place) and by one thread, repeated; every concurrent answer must be bit-identical
// to the single-threaded one. A plugin that keeps traversal state in the instance (a shared stack, a "current
// ray" member) gives different answers, or crashes, under contention. The first calls into the fresh instance
// are a concurrent round: a plugin that finishes its work lazily on first use (the tree built by the first
// query, without a lock) races only there.
//
// determinism: two builds of the same scene (two fresh instances) and a repeated query on one instance give
// bit-identical answers. A builder that depends on addresses, time or uninitialised memory does not.

#include "harness/grade/answers.h"
#include "harness/grade/checks.h"

#include <fmt/core.h>

#include <bit>
#include <chrono>
#include <exception>
#include <latch>
#include <mutex>
#include <thread>

namespace twinray::grade {

namespace {

constexpr std::size_t kDefaultRays = 20000;
constexpr std::size_t kDefaultDeterminismRays = 10000;  // per kind
// Rays per call. A race shows only while two calls are inside the plugin at once, so each call must be long
// against the cost of reaching the worker (which under a sanitizer build of twinray is most of a small call):
// at 256 rays per call the racy test plugin went undetected there; at 2048 the threads' calls overlap for
// most of their length. Still several calls per thread, starting at different places.
constexpr std::size_t kChunk = 2048;

struct Difference {
  std::size_t count = 0;
  std::optional<std::size_t> first;
};

Difference differences(const Answers& a, const Answers& b) {
  Difference d;
  for (std::size_t i = 0; i < a.hits.size(); ++i) {
    const bool differ = !same_bits(a.hits[i], b.hits[i]) || a.occluded[i] != b.occluded[i];
    d.count += differ ? 1 : 0;
    if (differ && !d.first) d.first = i;
  }
  return d;
}

// Every ray through `backend` on this thread, in chunks starting at chunk `start` and wrapping around.
void trace_rotated(const Backend& backend, std::span<const Ray> rays, std::size_t start, Answers& out) {
  out.hits.assign(rays.size(), Hit{});
  out.occluded.assign(rays.size(), 0);
  const std::size_t chunks = (rays.size() + kChunk - 1) / kChunk;
  for (std::size_t k = 0; k < chunks; ++k) {
    const std::size_t c = (start + k) % chunks;
    const std::size_t begin = c * kChunk, n = std::min(kChunk, rays.size() - begin);
    backend.intersect(rays.subspan(begin, n), std::span<Hit>(out.hits).subspan(begin, n));
    backend.occluded(rays.subspan(begin, n), std::span<std::uint8_t>(out.occluded).subspan(begin, n));
  }
}

}  // namespace

CheckVerdict run_thread_safety_check(CheckContext& ctx) {
  const std::vector<Ray> rays = ctx.rays_of_kinds({crosscheck::RayKind::Diffuse}, ctx.count_or(kDefaultRays));
  PluginInstance plugin = ctx.built_plugin();
  const auto threads = static_cast<std::size_t>(ctx.spec.threads);
  const std::size_t chunks = (rays.size() + kChunk - 1) / kChunk;
  // Every thread's answers to every ray, all threads released together.
  const auto concurrent_round = [&] {
    std::vector<Answers> results(threads);
    std::vector<std::exception_ptr> failures(threads);
    {
      // Every thread waits at the latch, so all of them reach the plugin together.
      std::latch start(static_cast<std::ptrdiff_t>(threads));
      std::vector<std::jthread> pool;
      for (std::size_t t = 0; t < threads; ++t)
        pool.emplace_back([&, t] {
          start.arrive_and_wait();
          try {
            trace_rotated(*plugin, rays, t * chunks / threads, results[t]);
          } catch (...) {
            failures[t] = std::current_exception();
          }
        });
    }
    // A crash of the worker fails every thread's call; the first failure stands for all of them.
    for (const std::exception_ptr& f : failures)
      if (f) std::rethrow_exception(f);
    return results;
  };
  const auto started = std::chrono::steady_clock::now();
  std::vector<Answers> results = concurrent_round();
  Answers single;
  trace_rotated(*plugin, rays, 0, single);

  std::size_t differing = 0, compared = 0;
  std::string first;
  std::optional<std::size_t> first_ray;
  // At least `repeat` rounds, and more until `min_seconds` of concurrent work are done: a race shows only while
  // two threads are inside the plugin at once, which on a busy two-core machine can be rare. Never more than
  // half of the time left before the deadline is spent on extra rounds.
  int rounds = 0;
  const auto more_rounds = [&] {
    const auto now = std::chrono::steady_clock::now();
    if (rounds < ctx.spec.repeat) return true;
    const double elapsed = std::chrono::duration<double>(now - started).count();
    const double per_round = elapsed / rounds;
    const double left = std::chrono::duration<double>(ctx.deadline - now).count();
    return elapsed < ctx.spec.min_seconds && per_round < 0.5 * left;
  };
  for (; rounds == 0 || more_rounds(); ++rounds) {
    if (rounds > 0) results = concurrent_round();  // the first round ran before the single-threaded answers
    for (std::size_t t = 0; t < threads; ++t) {
      const Difference d = differences(single, results[t]);
      differing += d.count;
      compared += rays.size();
      if (d.first && first.empty()) {
        first = fmt::format("round {}, thread {}, ray {}: alone {}, concurrently {}", rounds + 1, t + 1, *d.first,
                            describe_hit(single.hits[*d.first]), describe_hit(results[t].hits[*d.first]));
        first_ray = d.first;
      }
    }
  }

  plugin.end();

  CheckVerdict v;
  v.passed = differing == 0;
  v.figures = {{"rays", rays.size()}, {"threads", threads}, {"rounds", rounds}, {"answers_compared", compared},
               {"differing", differing}};
  if (v.passed) {
    v.detail = fmt::format("{} rays on {} threads at once, {} rounds: every answer bit-identical to one thread's",
                           rays.size(), threads, rounds);
  } else {
    v.detail = fmt::format("{} of {} concurrent answers differ from the single-threaded ones ({} threads); first: {}",
                           differing, compared, threads, first);
    v.reproduce = ctx.grade_command();  // a race is not replayed by one ray
  }
  return v;
}

CheckVerdict run_determinism_check(CheckContext& ctx) {
  const std::vector<Ray> rays = ctx.rays_of_kinds({crosscheck::RayKind::Uniform, crosscheck::RayKind::Diffuse},
                                                  ctx.count_or(kDefaultDeterminismRays));
  PluginInstance a = ctx.built_plugin();
  const Answers first = trace_rays(*a, rays, Queries::Both);
  const Answers again = trace_rays(*a, rays, Queries::Both);
  const BuildStats sa = a->build_stats();
  a.end();
  PluginInstance b = ctx.built_plugin();
  const Answers rebuilt = trace_rays(*b, rays, Queries::Both);
  const BuildStats sb = b->build_stats();
  b.end();

  const Difference repeat = differences(first, again), builds = differences(first, rebuilt);
  CheckVerdict v;
  v.passed = repeat.count == 0 && builds.count == 0;
  v.figures = {{"rays", rays.size()},
               {"differ_on_repeat", repeat.count},
               {"differ_between_builds", builds.count},
               {"nodes", {sa.nodes, sb.nodes}},
               {"sah_cost", {sa.sah_cost, sb.sah_cost}}};
  if (v.passed) {
    v.detail = fmt::format("two builds and a repeated query give bit-identical answers on {} rays", rays.size());
  } else {
    const std::size_t i = builds.first ? *builds.first : *repeat.first;
    v.detail = fmt::format("answers differ on {} of {} rays between two builds and on {} when repeated; first, ray {}",
                           builds.count, rays.size(), repeat.count, i);
    v.reproduce = ctx.grade_command();
  }
  return v;
}

}  // namespace twinray::grade
