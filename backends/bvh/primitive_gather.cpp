#include "backends/bvh/primitive_gather.h"

#include "backends/bvh/bvh_builder_memory.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <immintrin.h>

#include <algorithm>
#include <array>

namespace twinray {

std::vector<Bounds3> primitive_bounds(const SceneGeometry& geometry) {
  std::vector<Bounds3> bounds;
  // Huge pages before the first touch (bvh_builder_memory.h): a few thousand page faults fewer per 1M triangles.
  resize_on_huge_pages(bounds, geometry.primitive_count());
  std::size_t at = 0;
  for (const TriangleMesh& mesh : geometry.meshes) {
    // Large meshes in parallel blocks: a linear pass that would otherwise run alone before the build.
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, mesh.indices.size(), 1u << 14),
                      [&, at](const tbb::blocked_range<std::size_t>& r) {
                        // Bounds3::of_point(p0).extend(p1).extend(p2) in SSE: glm::min(acc, x) is
                        // _mm_min_ps(x, acc) operand for operand (likewise max), so the bits are the same;
                        // 53 instructions a triangle in scalar glm, 45 here (callgrind, dragon).
                        const auto load = [](const glm::vec3& p) {  // (x, y, z, 0), no read past p.z
                          return _mm_movelh_ps(_mm_loadl_pi(_mm_setzero_ps(), reinterpret_cast<const __m64*>(&p.x)),
                                               _mm_load_ss(&p.z));
                        };
                        for (std::size_t i = r.begin(); i < r.end(); ++i) {
                          const glm::uvec3& tri = mesh.indices[i];
                          const __m128 p0 = load(mesh.positions[tri.x]), p1 = load(mesh.positions[tri.y]),
                                       p2 = load(mesh.positions[tri.z]);
                          const __m128 lo = _mm_min_ps(p2, _mm_min_ps(p1, p0)), hi = _mm_max_ps(p2, _mm_max_ps(p1, p0));
                          alignas(16) float l[4], h[4];
                          _mm_store_ps(l, lo);
                          _mm_store_ps(h, hi);
                          bounds[at + i] = Bounds3{{l[0], l[1], l[2]}, {h[0], h[1], h[2]}};
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

// Copies one triangle leaf to the store's slots [first_slot, end_slot): the leaf's triangles, then copies
// of its last one up to `end_slot`, the end of its last block when no other leaf follows it there
// (padding, keyed kPadding).
void copy_triangle_leaf(const TriangleIds& ids, std::span<const std::uint32_t> leaf, std::uint32_t first_slot,
                        std::uint32_t end_slot, PrimitiveStore& store) {
  const auto count = static_cast<std::uint32_t>(leaf.size());
  const TriangleMesh* mesh = nullptr;
  std::uint32_t index = 0;
  for (std::uint32_t j = 0; j < end_slot - first_slot; ++j) {
    if (j < count) mesh = &ids.mesh_of(leaf[j], index);  // padding repeats the last triangle
    const glm::uvec3& tri = mesh->indices[index];
    const std::uint32_t slot = first_slot + j;
    store.triangle_blocks[slot / kTriangleBlockLanes].set(slot % kTriangleBlockLanes, mesh->positions[tri.x],
                                                          mesh->positions[tri.y], mesh->positions[tri.z]);
    store.triangle_keys[slot] = j < count ? PrimitiveKey{mesh->geom_id, index}
                                          : PrimitiveKey{PrimitiveKey::kPadding, PrimitiveKey::kPadding};
  }
}

constexpr std::uint64_t blocks_for(std::uint64_t lanes) {
  return (lanes + kTriangleBlockLanes - 1) / kTriangleBlockLanes;
}

// Places triangle leaves in blocks, one leaf after another in the order given, and says where each one's
// padding ends.
//
// kBlockAligned: every leaf starts a new block and pads the rest of its last block.
// kSharedBlocks: a leaf never touches more blocks than ceil(count / 4), and within that rule goes where it
// wastes no lane. The blocks left partly filled (at most kOpenBlocks of them, none more than kReachBack
// blocks behind the newest) stay open: a leaf of up to four triangles goes into the oldest open block with
// room for it (first fit), a longer one starts in the newest block if that one is open and the leaf then
// still touches only ceil(count / 4) blocks, else a leaf starts a new block. A block that leaves the window
// is closed: the last leaf put in it pads it to its end. A leaf so shares blocks only with leaves stored
// near it (the wide tree numbers leaves node by node, so mostly its siblings and cousins), and the blocks
// a node's leaves use stay within about a kilobyte of each other.
//
// Measured on the wide tree's leaves (docs/bvh-backend.md, "Memory"): on a 1M-triangle soup the blocks are
// 58% full one leaf per block, 84% with next fit (one open block), 97% with four open blocks reaching eight
// blocks back; more open blocks or a longer reach gain under 1%.
class BlockPacker {
 public:
  static constexpr int kOpenBlocks = 4;
  static constexpr std::uint64_t kReachBack = 8;

  BlockPacker(LeafPacking packing, std::vector<std::uint32_t>& ends)
      : window_(packing == LeafPacking::kSharedBlocks ? kOpenBlocks : 0), ends_(ends) {}

  // The first slot of leaf `leaf` of `count` triangles (ends[leaf] is set when its padding is known).
  std::uint64_t place(std::size_t leaf, std::uint32_t count) {
    std::uint64_t first = 0;
    if (!place_in_open_block(leaf, count, first)) {
      std::uint64_t lane = 0;
      // A longer leaf may start in the newest block, if it is open and the leaf still touches only
      // ceil(count / 4) blocks from there.
      if (open_count_ > 0 && open_[open_count_ - 1].block + 1 == blocks_ && count > kTriangleBlockLanes &&
          open_[open_count_ - 1].used + count <= blocks_for(count) * kTriangleBlockLanes) {
        lane = open_[open_count_ - 1].used;
        --open_count_;  // the leaf fills it
        --blocks_;
      }
      first = blocks_ * kTriangleBlockLanes + lane;
      blocks_ += blocks_for(lane + count);
      const std::uint64_t end = first + count;
      ends_[leaf] = static_cast<std::uint32_t>(end);
      if (end % kTriangleBlockLanes != 0)
        open(Open{blocks_ - 1, static_cast<std::uint32_t>(end % kTriangleBlockLanes), leaf});
    }
    // Blocks too far behind the newest are closed.
    int kept = 0;
    for (int o = 0; o < open_count_; ++o) {
      if (blocks_ - open_[o].block > kReachBack) close(open_[o]);
      else open_[kept++] = open_[o];
    }
    open_count_ = kept;
    return first;
  }

  // Closes the open blocks; returns the number of slots.
  std::uint64_t finish() {
    for (int o = 0; o < open_count_; ++o) close(open_[o]);
    open_count_ = 0;
    return blocks_ * kTriangleBlockLanes;
  }

 private:
  struct Open {
    std::uint64_t block;
    std::uint32_t used;     // lanes 0..used-1 are taken
    std::size_t last_leaf;  // the leaf that ends at lane used - 1: it pads the block if it is closed so
  };

  bool place_in_open_block(std::size_t leaf, std::uint32_t count, std::uint64_t& first) {
    if (count > kTriangleBlockLanes) return false;
    for (int o = 0; o < open_count_; ++o) {
      Open& b = open_[o];
      if (b.used + count > kTriangleBlockLanes) continue;
      first = b.block * kTriangleBlockLanes + b.used;
      b.used += count;
      b.last_leaf = leaf;
      ends_[leaf] = static_cast<std::uint32_t>(first + count);
      if (b.used == kTriangleBlockLanes) remove_open(o);  // full: no longer open
      return true;
    }
    return false;
  }

  void open(const Open& b) {
    if (window_ == 0) return close(b);
    if (open_count_ == window_) {  // the oldest makes room
      close(open_[0]);
      remove_open(0);
    }
    open_[open_count_++] = b;
  }

  // Drops open block o, keeping the others oldest first.
  void remove_open(int o) {
    for (int m = o + 1; m < open_count_; ++m) open_[m - 1] = open_[m];
    --open_count_;
  }

  void close(const Open& b) { ends_[b.last_leaf] = static_cast<std::uint32_t>((b.block + 1) * kTriangleBlockLanes); }

  int window_;
  std::vector<std::uint32_t>& ends_;
  std::array<Open, kOpenBlocks> open_{};
  int open_count_ = 0;
  std::uint64_t blocks_ = 0;
};

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
                                         std::span<const LeafToGather> leaves, PrimitiveStore& store,
                                         LeafPacking packing) {
  const TriangleIds ids(geometry);
  std::vector<std::uint32_t> offsets(leaves.size());
  // Per triangle leaf, the slot after its last padding lane (BlockPacker).
  std::vector<std::uint32_t> ends(leaves.size());
  BlockPacker packer(packing, ends);
  std::uint64_t spheres = 0;
  for (std::size_t i = 0; i < leaves.size(); ++i) {
    const LeafToGather& leaf = leaves[i];
    if (leaf.spheres) {
      offsets[i] = static_cast<std::uint32_t>(spheres);
      spheres += leaf.count;
      continue;
    }
    offsets[i] = static_cast<std::uint32_t>(packer.place(i, leaf.count));
  }
  const std::uint64_t slots = packer.finish();
  store = PrimitiveStore{};
  // The store's arrays are build memory (PrimitiveStore::Array): huge pages from 4 MiB on (the store was
  // about 12 000 page faults of a 1M-triangle build on small pages), and resize() leaves them
  // uninitialised: every slot is written below, padding lanes included (copy_triangle_leaf writes up to a
  // leaf's end slot, and BlockPacker makes the end slots cover every lane of every block).
  store.triangle_blocks.resize(slots / kTriangleBlockLanes);
  store.triangle_keys.resize(slots);
  store.spheres.resize(spheres);
  store.sphere_keys.resize(spheres);

  const bool prefetch = ids.triangle_count() >= kPrefetchFrom;
  // Leaves write disjoint ranges of slots (two leaves may share a block, never a lane). A grain of 1024
  // leaves (a few thousand triangles) keeps the task overhead small against the copies.
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
        copy_triangle_leaf(ids, leaf_ids, offsets[i], ends[i], store);
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
