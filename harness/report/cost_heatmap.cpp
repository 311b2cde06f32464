#include "harness/report/cost_heatmap.h"

#include "core/camera/pinhole_camera.h"
#include "core/util/fp_mode.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <stdexcept>

namespace twinray::report {

CostImages traversal_cost_images(const Scene& scene, const Backend& backend) {
  if (!backend.traits().counts_traversal)
    throw std::invalid_argument(std::string(backend.name()) + " does not count its traversal");
  const PinholeCamera camera(scene.camera);
  CostImages out;
  out.nodes = Image(camera.width(), camera.height(), 1);
  out.primitives = Image(camera.width(), camera.height(), 1);
  tbb::parallel_for(tbb::blocked_range<int>(0, camera.height()), [&](const tbb::blocked_range<int>& rows) {
    const ScopedFlushDenormals ftz;
    for (int y = rows.begin(); y < rows.end(); ++y)
      for (int x = 0; x < camera.width(); ++x) {
        QueryStats stats;
        Hit hit;
        backend.intersect(camera.pixel_center_ray(x, y), hit, &stats);
        out.nodes.at(x, y) = static_cast<float>(stats.nodes_visited);
        out.primitives.at(x, y) = static_cast<float>(stats.primitives_tested);
      }
  });
  const double n = static_cast<double>(out.nodes.pixel_count());
  for (std::size_t i = 0; i < out.nodes.data.size(); ++i) {
    out.mean_nodes += out.nodes.data[i] / n;
    out.mean_primitives += out.primitives.data[i] / n;
  }
  return out;
}

}  // namespace twinray::report
