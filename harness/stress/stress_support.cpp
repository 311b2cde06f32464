#include "harness/stress/stress_support.h"

#include "backends/registry.h"
#include "core/scene/geometry_cleanup.h"

#include <algorithm>
#include <cmath>
#include <fmt/core.h>
#include <limits>

namespace twinray::stress {

std::unique_ptr<Backend> build_backend(const std::string& name, const SceneGeometry& geometry) {
  std::unique_ptr<Backend> backend = make_backend(name);
  backend->build(geometry);
  return backend;
}

bool is_fast_mode(const std::string& backend) { return backend == "embree-fast"; }

void set_requirement(Outcome& outcome, const std::string& backend, bool claimed, std::string_view property) {
  if (is_fast_mode(backend)) {
    outcome.required = false;
    if (outcome.note.empty()) outcome.note = "embree-fast: reported, not required";
  } else if (!claimed) {
    outcome.required = false;
    if (outcome.note.empty()) outcome.note = fmt::format("{} does not claim {}: reported, not required", backend, property);
  }
}

std::size_t scaled(std::size_t count, const StressOptions& options, std::size_t minimum) {
  const double n = std::round(static_cast<double>(count) * options.effort);
  return std::max(minimum, static_cast<std::size_t>(std::max(n, 0.0)));
}

int count_crossings(const Backend& backend, Ray ray, int limit) {
  int crossings = 0;
  Hit hit;
  while (crossings < limit && backend.intersect(ray, hit)) {
    ++crossings;
    ray.tmin = std::nextafter(hit.t, std::numeric_limits<float>::infinity());
    if (!(ray.tmin <= ray.tmax)) break;
  }
  return crossings;
}

Crossings classify_crossings(const Backend& backend, Ray ray, int limit) {
  Crossings c;
  Hit hit;
  float previous = -std::numeric_limits<float>::infinity();
  for (int n = 0; n < limit && backend.intersect(ray, hit); ++n) {
    float near_limit = previous;
    for (int i = 0; i < kSamePointUlps; ++i) near_limit = std::nextafter(near_limit, std::numeric_limits<float>::infinity());
    if (hit.t <= near_limit) ++c.same_point_duplicates;
    else ++c.distinct;
    previous = hit.t;
    ray.tmin = std::nextafter(hit.t, std::numeric_limits<float>::infinity());
    if (!(ray.tmin <= ray.tmax)) break;
  }
  return c;
}

TriangleMesh integer_box_mesh(int lo, int hi, std::uint32_t geom_id) {
  TriangleMesh mesh;
  mesh.geom_id = geom_id;
  const int n = hi - lo;
  // Each face: a fixed axis and side, and two in-plane axes (a, b) ordered so that cross(a, b) points out.
  struct Face {
    int axis, a, b;
    bool high;
  };
  const Face faces[6] = {{0, 2, 1, false}, {0, 1, 2, true}, {1, 0, 2, false},
                         {1, 2, 0, true},  {2, 1, 0, false}, {2, 0, 1, true}};
  for (const Face& f : faces) {
    const auto base = static_cast<std::uint32_t>(mesh.positions.size());
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) {
        glm::vec3 p(0.0f);
        p[f.axis] = static_cast<float>(f.high ? hi : lo);
        p[f.a] = static_cast<float>(lo + i);
        p[f.b] = static_cast<float>(lo + j);
        mesh.positions.push_back(p);
      }
    const auto row = static_cast<std::uint32_t>(n + 1);
    for (std::uint32_t j = 0; j < static_cast<std::uint32_t>(n); ++j)
      for (std::uint32_t i = 0; i < static_cast<std::uint32_t>(n); ++i) {
        const std::uint32_t v00 = base + j * row + i, v10 = v00 + 1, v01 = v00 + row, v11 = v01 + 1;
        // Alternate the diagonal so both vertex valences occur, as in procedural grid_mesh.
        if (((i + j) & 1u) == 0) {
          mesh.indices.push_back({v00, v10, v11});
          mesh.indices.push_back({v00, v11, v01});
        } else {
          mesh.indices.push_back({v00, v10, v01});
          mesh.indices.push_back({v10, v11, v01});
        }
      }
  }
  ensure_vertex_padding(mesh.positions);
  return mesh;
}

double relative_difference(double a, double b) {
  const double m = std::max(std::fabs(a), std::fabs(b));
  return m == 0.0 ? 0.0 : std::fabs(a - b) / m;
}

}  // namespace twinray::stress
