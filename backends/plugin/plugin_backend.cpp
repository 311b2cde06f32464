#include "backends/plugin/plugin_backend.h"

#include "backends/plugin/plugin_failure.h"
#include "backends/plugin/plugin_hit.h"
#include "backends/plugin/plugin_library.h"
#include "backends/plugin/twinray_plugin.h"

#include <algorithm>
#include <cassert>
#include <chrono>
#include <cstdint>
#include <exception>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace twinray {

namespace {

// Rays handed to an optional batch entry point per call; the staging buffers live on the stack.
constexpr std::size_t kBatchChunk = 256;

void add_stats(QueryStats* stats, std::size_t queries, const twinray_query_stats& plugin) {
  if (stats == nullptr) return;
  stats->queries += queries;
  stats->nodes_visited += plugin.nodes_visited;
  stats->primitives_tested += plugin.primitives_tested;
}

class PluginBackend final : public Backend {
 public:
  explicit PluginBackend(std::unique_ptr<PluginLibrary> library)
      : library_(std::move(library)), table_(library_->table()), self_(library_->self()),
        name_(library_->backend_name()) {}

  std::string_view name() const override { return name_; }

  BackendTraits traits() const override {
    BackendTraits t;
    t.counts_traversal = (table_.flags & TWINRAY_PLUGIN_COUNTS_TRAVERSAL) != 0;
    t.honours_ties = (table_.flags & TWINRAY_PLUGIN_HONOURS_TIES) != 0;
    t.watertight = (table_.flags & TWINRAY_PLUGIN_WATERTIGHT) != 0;
    return t;
  }

  void build(const SceneGeometry& geometry) override;
  BuildStats build_stats() const override { return stats_; }

  bool intersect(const Ray& ray, Hit& hit, QueryStats* stats) const override {
    hit = Hit{};
    twinray_query_stats counters{};
    bool found = false;
    if (is_valid_ray(ray)) {
      const twinray_ray r = to_plugin_ray(ray);
      twinray_hit h = plugin_miss();
      guarded("intersect1", [&] { found = table_.intersect1(self_, &r, &h, &counters) != 0; });
      if (found) accept_hit(h, hit);
    }
    add_stats(stats, 1, counters);
    return found;
  }

  bool occluded(const Ray& ray, QueryStats* stats) const override {
    twinray_query_stats counters{};
    bool blocked = false;
    if (is_valid_ray(ray)) {
      const twinray_ray r = to_plugin_ray(ray);
      guarded("occluded1", [&] { blocked = table_.occluded1(self_, &r, &counters) != 0; });
    }
    add_stats(stats, 1, counters);
    return blocked;
  }

  void intersect(std::span<const Ray> rays, std::span<Hit> hits, QueryStats* stats) const override;
  void occluded(std::span<const Ray> rays, std::span<std::uint8_t> occluded, QueryStats* stats) const override;

 private:
  // Runs a plugin call and turns an escaping C++ exception (a contract violation, but a common one in
  // plugins written in C++) into an error that names the plugin.
  template <typename F>
  void guarded(const char* what, F&& call) const {
    try {
      call();
    } catch (const std::exception& e) {
      throw std::runtime_error(name_ + ": " + what + " threw: " + e.what());
    } catch (...) {
      throw std::runtime_error(name_ + ": " + what + " threw a non-standard exception");
    }
  }

  // See plugin_hit.h: only a hit on a primitive that does not exist is refused.
  void accept_hit(const twinray_hit& h, Hit& hit) const {
    if (!primitives_.exists(h.geom_id, h.prim_id)) throw std::runtime_error(nonexistent_primitive_message(name_, h));
    hit = from_plugin_hit(h);
  }

  std::unique_ptr<PluginLibrary> library_;  // destroys the instance, then closes the library
  const twinray_plugin_v1& table_;
  void* self_;
  std::string name_;
  // What the plugin reads during and after build (twinray_plugin.h: valid until destroy).
  std::vector<twinray_mesh> meshes_;
  std::vector<twinray_sphere> spheres_;
  PrimitiveIndex primitives_;
  BuildStats stats_;
};

void PluginBackend::build(const SceneGeometry& geometry) {
  const auto start = std::chrono::steady_clock::now();
  primitives_ = PrimitiveIndex(geometry);
  meshes_.clear();
  spheres_.clear();
  for (const TriangleMesh& m : geometry.meshes) {
    twinray_mesh pm;
    pm.geom_id = m.geom_id;
    pm.positions = reinterpret_cast<const float*>(m.positions.data());
    pm.vertex_count = m.positions.size();
    pm.indices = reinterpret_cast<const twinray_id*>(m.indices.data());
    pm.triangle_count = m.indices.size();
    meshes_.push_back(pm);
  }
  for (const Sphere& s : geometry.spheres) spheres_.push_back(to_plugin_sphere(s));
  twinray_geometry g;
  g.meshes = meshes_.data();
  g.mesh_count = meshes_.size();
  g.spheres = spheres_.data();
  g.sphere_count = spheres_.size();
  g.geom_id_end = geometry.geom_id_end();

  char error[1024] = {};
  int status = TWINRAY_ERROR;
  guarded("build", [&] { status = table_.build(self_, &g, error, sizeof(error)); });
  if (status != TWINRAY_OK) {
    error[sizeof(error) - 1] = '\0';  // do not trust the plugin to terminate it
    throw PluginBuildError(name_ + " (" + library_->path().string() + "): build failed: " +
                             (error[0] != '\0' ? error : "no message given"));
  }

  stats_ = BuildStats{};
  stats_.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  stats_.triangles = geometry.triangle_count();
  stats_.spheres = geometry.sphere_count();
  // What twinray handed over; whether the plugin builds anything for an empty kind is its own business.
  stats_.built_triangles = geometry.has_triangles();
  stats_.built_spheres = geometry.has_spheres();
  if (table_.build_stats != nullptr) {
    twinray_build_stats ps{};
    guarded("build_stats", [&] { table_.build_stats(self_, &ps); });
    stats_.memory_bytes = ps.memory_bytes;
    stats_.nodes = ps.nodes;
    stats_.leaves = ps.leaves;
    stats_.max_depth = ps.max_depth;
    stats_.sah_cost = ps.sah_cost;
  }
}

// With a batch entry point: invalid rays are filtered out (they are misses), the valid ones are staged in
// chunks and passed on. Without one, the base class loops over the single-ray calls.
void PluginBackend::intersect(std::span<const Ray> rays, std::span<Hit> hits, QueryStats* stats) const {
  assert(rays.size() == hits.size());
  if (table_.intersect_batch == nullptr) return Backend::intersect(rays, hits, stats);
  twinray_ray staged[kBatchChunk];
  twinray_hit results[kBatchChunk];
  std::size_t source[kBatchChunk];
  twinray_query_stats counters{};
  for (std::size_t begin = 0; begin < rays.size(); begin += kBatchChunk) {
    const std::size_t end = std::min(rays.size(), begin + kBatchChunk);
    std::size_t count = 0;
    for (std::size_t i = begin; i < end; ++i) {
      hits[i] = Hit{};
      if (!is_valid_ray(rays[i])) continue;
      staged[count] = to_plugin_ray(rays[i]);
      results[count] = plugin_miss();
      source[count++] = i;
    }
    if (count == 0) continue;
    guarded("intersect_batch", [&] { table_.intersect_batch(self_, staged, results, count, &counters); });
    for (std::size_t k = 0; k < count; ++k)
      if (results[k].geom_id != TWINRAY_INVALID_ID) accept_hit(results[k], hits[source[k]]);
  }
  add_stats(stats, rays.size(), counters);
}

void PluginBackend::occluded(std::span<const Ray> rays, std::span<std::uint8_t> occluded, QueryStats* stats) const {
  assert(rays.size() == occluded.size());
  if (table_.occluded_batch == nullptr) return Backend::occluded(rays, occluded, stats);
  twinray_ray staged[kBatchChunk];
  unsigned char results[kBatchChunk];
  std::size_t source[kBatchChunk];
  twinray_query_stats counters{};
  for (std::size_t begin = 0; begin < rays.size(); begin += kBatchChunk) {
    const std::size_t end = std::min(rays.size(), begin + kBatchChunk);
    std::size_t count = 0;
    for (std::size_t i = begin; i < end; ++i) {
      occluded[i] = 0;
      if (!is_valid_ray(rays[i])) continue;
      staged[count] = to_plugin_ray(rays[i]);
      results[count] = 0;
      source[count++] = i;
    }
    if (count == 0) continue;
    guarded("occluded_batch", [&] { table_.occluded_batch(self_, staged, results, count, &counters); });
    for (std::size_t k = 0; k < count; ++k) occluded[source[k]] = results[k] != 0 ? 1 : 0;
  }
  add_stats(stats, rays.size(), counters);
}

}  // namespace

std::unique_ptr<Backend> load_plugin_backend(const std::filesystem::path& so) {
  return std::make_unique<PluginBackend>(PluginLibrary::load(so));
}

}  // namespace twinray
