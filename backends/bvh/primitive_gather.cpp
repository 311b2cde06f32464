#include "backends/bvh/primitive_gather.h"

#include "backends/bvh/bvh_builder_memory.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>

namespace twinray {

std::vector<Bounds3> primitive_bounds(const SceneGeometry& geometry) {
  std::vector<Bounds3> bounds;
  // Huge pages before the first touch (bvh_builder_memory.h): a few thousand page faults fewer per 1M triangles.
  bounds.reserve(geometry.primitive_count());
  advise_huge_pages(bounds.data(), geometry.primitive_count() * sizeof(Bounds3));
  bounds.resize(geometry.primitive_count());
  std::size_t at = 0;
  for (const TriangleMesh& mesh : geometry.meshes) {
    // Large meshes in parallel blocks: a linear pass that would otherwise run alone before the build.
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, mesh.indices.size(), 1u << 14),
                      [&, at](const tbb::blocked_range<std::size_t>& r) {
                        for (std::size_t i = r.begin(); i < r.end(); ++i) {
                          const glm::uvec3& tri = mesh.indices[i];
                          Bounds3 b = Bounds3::of_point(mesh.positions[tri.x]);
                          b.extend(mesh.positions[tri.y]);
                          b.extend(mesh.positions[tri.z]);
                          bounds[at + i] = b;
                        }
                      });
    at += mesh.indices.size();
  }
  for (const Sphere& s : geometry.spheres) bounds[at++] = s.bounds();
  return bounds;
}

namespace {

// Triangle primitive id -> (mesh, index in mesh): ids number the meshes' triangles one mesh after another,
// so the mesh is found by a binary search over their first ids (no per-triangle table to build).
class TriangleIds {
 public:
  explicit TriangleIds(const SceneGeometry& geometry) : geometry_(geometry) {
    first_.reserve(geometry.meshes.size() + 1);
    std::uint32_t at = 0;
    for (const TriangleMesh& mesh : geometry.meshes) {
      first_.push_back(at);
      at += static_cast<std::uint32_t>(mesh.indices.size());
    }
    first_.push_back(at);
  }
  std::uint32_t triangle_count() const { return first_.back(); }
  // The mesh holding triangle `id` (< triangle_count()) and the triangle's index in it. Empty meshes share
  // their first id with the next one; upper_bound skips them.
  const TriangleMesh& mesh_of(std::uint32_t id, std::uint32_t& index) const {
    if (first_.size() == 2) {  // one mesh, the common case: no search
      index = id;
      return geometry_.meshes[0];
    }
    const auto m = static_cast<std::size_t>(std::upper_bound(first_.begin(), first_.end(), id) - first_.begin()) - 1;
    index = id - first_[m];
    return geometry_.meshes[m];
  }

 private:
  const SceneGeometry& geometry_;
  std::vector<std::uint32_t> first_;
};

// Copies one triangle leaf to the store, starting at `first_slot` (a block's first lane): the leaf's
// triangles, then copies of its last one up to the end of its last block (padding, keyed kPadding).
void copy_triangle_leaf(const TriangleIds& ids, std::span<const std::uint32_t> leaf, std::uint32_t first_slot,
                        PrimitiveStore& store) {
  const auto count = static_cast<std::uint32_t>(leaf.size());
  const std::uint32_t slots = (count + kTriangleBlockLanes - 1) / kTriangleBlockLanes * kTriangleBlockLanes;
  const TriangleMesh* mesh = nullptr;
  std::uint32_t index = 0;
  for (std::uint32_t j = 0; j < slots; ++j) {
    if (j < count) mesh = &ids.mesh_of(leaf[j], index);  // padding repeats the last triangle
    const glm::uvec3& tri = mesh->indices[index];
    const std::uint32_t slot = first_slot + j;
    store.triangle_blocks[slot / kTriangleBlockLanes].set(slot % kTriangleBlockLanes, mesh->positions[tri.x],
                                                          mesh->positions[tri.y], mesh->positions[tri.z]);
    store.triangle_keys[slot] = j < count ? PrimitiveKey{mesh->geom_id, index}
                                          : PrimitiveKey{PrimitiveKey::kPadding, PrimitiveKey::kPadding};
  }
}

// Leaves are copied in tree order, which reads the meshes in no particular order: on a large scene every
// triangle costs two dependent cache misses (its indices, then its vertices), which dominated the gather
// (a fifth of a bvh8 build of a 1M-triangle soup). So the copy of leaf i is preceded by prefetches: the
// indices of the triangles kIndexAhead leaves ahead, and the vertices of those kVertexAhead leaves ahead
// (whose indices were prefetched earlier), so that the misses of many triangles overlap. Prefetches
// change no result. Below kPrefetchFrom triangles (a few MB of indices and vertices, which stay in the
// caches) they are skipped: on the dragon (100k) they doubled the gather's instructions for nothing.
constexpr std::size_t kIndexAhead = 16, kVertexAhead = 8;
constexpr std::uint32_t kPrefetchFrom = 1u << 18;

void prefetch_indices(const TriangleIds& ids, std::span<const std::uint32_t> leaf) {
  for (const std::uint32_t id : leaf) {
    std::uint32_t index = 0;
    const TriangleMesh& mesh = ids.mesh_of(id, index);
    __builtin_prefetch(&mesh.indices[index]);
  }
}

void prefetch_vertices(const TriangleIds& ids, std::span<const std::uint32_t> leaf) {
  for (const std::uint32_t id : leaf) {
    std::uint32_t index = 0;
    const TriangleMesh& mesh = ids.mesh_of(id, index);
    const glm::uvec3& tri = mesh.indices[index];
    __builtin_prefetch(&mesh.positions[tri.x]);
    __builtin_prefetch(&mesh.positions[tri.y]);
    __builtin_prefetch(&mesh.positions[tri.z]);
  }
}

}  // namespace

std::vector<std::uint32_t> gather_leaves(const SceneGeometry& geometry, std::span<const std::uint32_t> prim_order,
                                         std::span<const LeafToGather> leaves, PrimitiveStore& store) {
  const TriangleIds ids(geometry);
  std::vector<std::uint32_t> offsets(leaves.size());
  std::uint64_t slots = 0, spheres = 0;
  for (std::size_t i = 0; i < leaves.size(); ++i) {
    const LeafToGather& leaf = leaves[i];
    std::uint64_t& next = leaf.spheres ? spheres : slots;
    offsets[i] = static_cast<std::uint32_t>(next);
    next += leaf.spheres ? leaf.count : (leaf.count + kTriangleBlockLanes - 1) / kTriangleBlockLanes * kTriangleBlockLanes;
  }
  store = PrimitiveStore{};
  // Huge pages before resize() first touches them (bvh_builder_memory.h): the store was about 12 000 page
  // faults of a 1M-triangle build.
  const auto advise = [](auto& v, std::size_t n) {
    v.reserve(n);
    advise_huge_pages(v.data(), n * sizeof(v[0]));
  };
  advise(store.triangle_blocks, slots / kTriangleBlockLanes);
  advise(store.triangle_keys, slots);
  store.triangle_blocks.resize(slots / kTriangleBlockLanes);
  store.triangle_keys.resize(slots);
  store.spheres.resize(spheres);
  store.sphere_keys.resize(spheres);

  const bool prefetch = ids.triangle_count() >= kPrefetchFrom;
  // Leaves write disjoint ranges. A grain of 1024 leaves (a few thousand triangles) keeps the task
  // overhead small against the copies.
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves.size(), 1024), [&](const tbb::blocked_range<std::size_t>& r) {
    const auto ids_of = [&](std::size_t i) { return prim_order.subspan(leaves[i].first, leaves[i].count); };
    const auto ahead = [&](std::size_t i, std::size_t by) {
      return prefetch && i + by < r.end() && !leaves[i + by].spheres;
    };
    for (std::size_t i = r.begin(); i < std::min(r.end(), r.begin() + kIndexAhead); ++i)
      if (ahead(r.begin(), i - r.begin())) prefetch_indices(ids, ids_of(i));
    for (std::size_t i = r.begin(); i < std::min(r.end(), r.begin() + kVertexAhead); ++i)
      if (ahead(r.begin(), i - r.begin())) prefetch_vertices(ids, ids_of(i));
    for (std::size_t i = r.begin(); i < r.end(); ++i) {
      const LeafToGather& leaf = leaves[i];
      const std::span<const std::uint32_t> leaf_ids = ids_of(i);
      if (ahead(i, kIndexAhead)) prefetch_indices(ids, ids_of(i + kIndexAhead));
      if (ahead(i, kVertexAhead)) prefetch_vertices(ids, ids_of(i + kVertexAhead));
      if (!leaf.spheres) {
        copy_triangle_leaf(ids, leaf_ids, offsets[i], store);
        continue;
      }
      for (std::uint32_t j = 0; j < leaf.count; ++j) {
        const Sphere& s = geometry.spheres[leaf_ids[j] - ids.triangle_count()];
        store.spheres[offsets[i] + j] = {s.center, s.radius};
        store.sphere_keys[offsets[i] + j] = {s.geom_id, 0};
      }
    }
  });
  return offsets;
}

}  // namespace twinray
