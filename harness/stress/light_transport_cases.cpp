// Light-transport cases: scenes whose answer is known in closed form (or must at least stay finite),
// rendered by the path integrator (MIS) over each backend. Every case reports the error against the
// analytic value, the render time, and the count of NaN/Inf and negative samples (which must be 0).
// Sources and reasoning: docs/stress.md.

#include "harness/stress/stress_case.h"
#include "harness/stress/stress_support.h"
#include "core/camera/pinhole_camera.h"
#include "core/image/image_io.h"
#include "core/lights/environment_light.h"
#include "core/render/renderer.h"
#include "core/scene/procedural.h"

#include <fmt/core.h>
#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <numbers>
#include <unistd.h>
#include <vector>

namespace twinray::stress {

namespace {

std::uint32_t add_material(Scene& scene, MaterialType type, glm::vec3 albedo, float ior = 1.5f,
                           glm::vec3 radiance = glm::vec3(0.0f)) {
  Material m;
  m.type = type;
  m.albedo = albedo;
  m.ior = ior;
  m.radiance = radiance;
  scene.materials.push_back(m);
  return static_cast<std::uint32_t>(scene.materials.size() - 1);
}

void add_mesh(Scene& scene, TriangleMesh mesh, std::uint32_t material) {
  mesh.geom_id = static_cast<std::uint32_t>(scene.shapes.size());
  if (mesh.positions.capacity() <= mesh.positions.size()) mesh.positions.reserve(mesh.positions.size() + 1);
  scene.geometry.meshes.push_back(std::move(mesh));
  scene.shapes.push_back({"mesh", ShapeKind::Mesh, material, {}});
}

void add_sphere(Scene& scene, glm::vec3 center, float radius, std::uint32_t material) {
  scene.geometry.spheres.push_back({static_cast<std::uint32_t>(scene.shapes.size()), center, radius});
  scene.shapes.push_back({"sphere", ShapeKind::Sphere, material, {}});
}

// A parallelogram p, p+a, p+a+b, p+b whose front (cross(a, b)) is the visible side.
TriangleMesh quad(glm::vec3 p, glm::vec3 a, glm::vec3 b) {
  TriangleMesh m;
  m.positions = {p, p + a, p + a + b, p + b};
  m.indices = {{0, 1, 2}, {0, 2, 3}};
  return m;
}

Scene base_scene(glm::vec3 eye, glm::vec3 target, float vfov, int size) {
  Scene s;
  s.camera.position = eye;
  s.camera.look_at = target;
  s.camera.up = {0.0f, 1.0f, 0.0f};
  s.camera.vfov_deg = vfov;
  s.camera.width = size;
  s.camera.height = size;
  return s;
}

struct Measured {
  double mean = 0.0;           // over pixels and channels
  double standard_error = 0.0;
  double expected = 0.0;
  double seconds = 0.0;
  std::uint64_t nonfinite = 0, negative = 0;
};

// Renders with the path integrator (MIS, unlimited depth unless given) and compares the image mean with
// `expected(x, y)` averaged over the pixels (per-pixel expectations at pixel centres).
Measured render_and_measure(const Scene& scene, const std::string& backend_name, int spp,
                            const std::function<double(int, int)>& expected, int max_depth = -1) {
  const auto backend = build_backend(backend_name, scene.geometry);
  RenderOptions opt;
  opt.integrator = IntegratorKind::Path;
  opt.settings.max_depth = max_depth;
  opt.spp = spp;
  opt.seed = 1;
  opt.show_progress = false;
  const RenderSetup setup(scene, opt, backend->traits());
  const RenderResult r = render(setup, *backend);
  const Image mean = r.film.mean_image();
  const Image var = r.film.variance_of_mean_image();
  Measured m;
  double sum = 0.0, var_sum = 0.0, exp_sum = 0.0;
  for (int y = 0; y < mean.height; ++y)
    for (int x = 0; x < mean.width; ++x) {
      for (int c = 0; c < 3; ++c) {
        sum += mean.at(x, y, c);
        var_sum += var.at(x, y, c);
      }
      exp_sum += 3.0 * expected(x, y);
    }
  const double n = 3.0 * static_cast<double>(mean.pixel_count());
  m.mean = sum / n;
  // Channels of one pixel are correlated (same paths): count them as one to stay conservative.
  m.standard_error = std::sqrt(3.0 * var_sum) / n;
  m.expected = exp_sum / n;
  m.seconds = r.stats.seconds;
  m.nonfinite = r.stats.nonfinite_samples;
  m.negative = r.stats.negative_samples;
  return m;
}

// Statistical agreement: within 4 standard errors plus 0.5% (float accumulation and the pixel-centre
// approximation of smooth expectations), and no NaN/Inf or negative sample at all.
bool agrees(const Measured& m) {
  return std::fabs(m.mean - m.expected) <= 4.0 * m.standard_error + 5e-3 * std::fabs(m.expected) &&
         m.nonfinite == 0 && m.negative == 0;
}

std::string describe(const char* label, const Measured& m) {
  return fmt::format("{}: {:.5g} vs {:.5g} (err {:.2g}, 4se {:.2g}), {:.2f} s, NaN/Inf {}, neg {}", label, m.mean,
                     m.expected, std::fabs(m.mean - m.expected), 4.0 * m.standard_error, m.seconds, m.nonfinite,
                     m.negative);
}

nlohmann::json to_json(const Measured& m) {
  return {{"mean", m.mean},     {"expected", m.expected},   {"standard_error", m.standard_error},
          {"seconds", m.seconds}, {"nonfinite_samples", m.nonfinite}, {"negative_samples", m.negative}};
}

Outcome finish(Outcome out, const std::string& backend_name, const std::vector<std::pair<std::string, Measured>>& parts) {
  bool ok = true;
  for (const auto& [label, m] : parts) {
    ok = ok && agrees(m);
    out.figures += (out.figures.empty() ? "" : "; ") + describe(label.c_str(), m);
    out.json[label] = to_json(m);
  }
  out.status = ok ? Status::Pass : Status::Fail;
  set_requirement(out, backend_name, true, "");
  return out;
}

int image_size(const StressOptions& o) { return o.effort >= 0.5 ? 24 : 12; }
int spp_for(int base, const StressOptions& o) { return std::max(4, static_cast<int>(std::lround(base * o.effort))); }

// Inside a closed box whose walls all emit Le and reflect diffusely with albedo a, every point sees
// L = Le / (1 - a) (the Neumann series of a uniform furnace). a = 0.9 makes the average path 10 segments
// long, so Russian roulette and throughput bookkeeping are exercised far beyond the usual depth.
Outcome furnace_long_paths(const std::string& backend_name, const StressOptions& options) {
  Scene scene = base_scene({0.3f, 0.2f, 0.1f}, {-1.0f, -0.5f, -2.0f}, 90.0f, image_size(options));
  const float le = 0.1f, a = 0.9f;
  const std::uint32_t wall = add_material(scene, MaterialType::Emissive, glm::vec3(a), 1.5f, glm::vec3(le));
  TriangleMesh box = integer_box_mesh(-2, 2);
  for (glm::uvec3& t : box.indices) std::swap(t[1], t[2]);  // faces point inward
  add_mesh(scene, std::move(box), wall);
  const double expected = le / (1.0 - a);
  return finish({}, backend_name,
                {{"closed furnace a=0.9", render_and_measure(scene, backend_name, spp_for(64, options),
                                                             [&](int, int) { return expected; })}});
}

// A lossless dielectric in a uniform environment redistributes radiance without changing it: every pixel
// must be exactly the environment's radiance. ior 1.0001 (almost no refraction: Fresnel ~ 2.5e-9, the
// refracted direction differs from the incident one in the last bits), 1.5, and 4.0 (critical angle 14.5
// degrees: most internal paths are totally reflected many times). Analytic spheres and a tessellated one.
Outcome glass_furnace(const std::string& backend_name, const StressOptions& options) {
  std::vector<std::pair<std::string, Measured>> parts;
  for (const float ior : {1.0001f, 1.5f, 4.0f}) {
    for (const bool tessellated : {false, true}) {
      if (tessellated && ior != 4.0f) continue;
      Scene scene = base_scene({0.0f, 0.0f, 3.0f}, {0.0f, 0.0f, 0.0f}, 40.0f, image_size(options));
      scene.environment.type = EnvironmentType::Constant;
      scene.environment.radiance = glm::vec3(1.0f);
      const std::uint32_t glass = add_material(scene, MaterialType::Glass, glm::vec3(0.0f), ior);
      if (tessellated) add_mesh(scene, tessellated_sphere({0, 0, 0}, 1.0f, 3).meshes.front(), glass);
      else add_sphere(scene, {0, 0, 0}, 1.0f, glass);
      parts.push_back({fmt::format("{} ior {:g}", tessellated ? "mesh" : "sphere", ior),
                       render_and_measure(scene, backend_name, spp_for(32, options), [](int, int) { return 1.0; })});
    }
  }
  return finish({}, backend_name, parts);
}

// A 1e-3 x 1e-3 light of radiance 1e6 one unit above a diffuse floor (albedo 0.5). Unidirectional BSDF
// sampling would find it with probability ~1e-6 per bounce (fireflies); with light sampling and MIS the
// floor converges to E rho / pi with E = Le A cos^2 / r^2 = Le A h^2 / r^4 (small-source limit, relative
// error ~ (size / r)^2 = 1e-6). The camera looks from above, so the light shows its black back.
Outcome tiny_bright_light(const std::string& backend_name, const StressOptions& options) {
  const int size = image_size(options);
  Scene scene = base_scene({0.0f, 2.5f, 2.0f}, {0.0f, 0.0f, 0.0f}, 50.0f, size);
  const float rho = 0.5f, le = 1e6f, s = 1e-3f, h = 1.0f;
  const std::uint32_t floor_material = add_material(scene, MaterialType::Diffuse, glm::vec3(rho));
  const std::uint32_t light = add_material(scene, MaterialType::Emissive, glm::vec3(0.0f), 1.5f, glm::vec3(le));
  add_mesh(scene, quad({-50.0f, 0.0f, 50.0f}, {100.0f, 0.0f, 0.0f}, {0.0f, 0.0f, -100.0f}), floor_material);
  // Facing down: cross(a, b) = -y.
  add_mesh(scene, quad({-0.5f * s, h, -0.5f * s}, {s, 0.0f, 0.0f}, {0.0f, 0.0f, s}), light);
  const PinholeCamera camera(scene.camera);
  const auto expected = [&](int x, int y) {
    const Ray ray = camera.pixel_center_ray(x, y);
    if (ray.dir.y >= 0.0f) return 0.0;
    const double t = -static_cast<double>(ray.org.y) / ray.dir.y;
    const double px = ray.org.x + t * ray.dir.x, pz = ray.org.z + t * ray.dir.z;
    const double r2 = px * px + pz * pz + static_cast<double>(h) * h;
    return rho / std::numbers::pi * le * s * s * h * h / (r2 * r2);
  };
  return finish({}, backend_name,
                {{"tiny light", render_and_measure(scene, backend_name, spp_for(64, options), expected)}});
}

// Exact irradiance of an upward-facing plane under a latitude-longitude map with nearest-texel lookup:
// sum over texel rows above the horizon of L * dphi * (sin^2 theta_b - sin^2 theta_a) / 2.
glm::dvec3 upper_hemisphere_irradiance(const EnvironmentLight& env, int width, int height) {
  glm::dvec3 e(0.0);
  const double pi = std::numbers::pi;
  for (int j = 0; j < height / 2; ++j) {
    const double ta = pi * j / height, tb = pi * (j + 1) / height, tc = 0.5 * (ta + tb);
    const double weight = (2.0 * pi / width) * 0.5 * (std::sin(tb) * std::sin(tb) - std::sin(ta) * std::sin(ta));
    for (int i = 0; i < width; ++i) {
      const double phi = 2.0 * pi * ((i + 0.5) / width - 0.5);
      const glm::vec3 dir(static_cast<float>(std::sin(tc) * std::sin(phi)), static_cast<float>(std::cos(tc)),
                          static_cast<float>(-std::sin(tc) * std::cos(phi)));
      e += weight * glm::dvec3(env.eval(dir));
    }
  }
  return e;
}

// A diffuse floor under an environment map whose energy sits in a few very bright texels: without
// importance sampling almost every sample misses the sun. Expected: rho / pi * E, E summed exactly over
// the texels. A synthetic map (always) and the studio map from $TWINRAY_SHARED (when present).
Outcome environment_small_sources(const std::string& backend_name, const StressOptions& options) {
  std::vector<std::pair<std::string, Measured>> parts;
  Outcome out;
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / fmt::format("twinray-stress-env-{}", ::getpid());
  std::filesystem::create_directories(dir);
  Image synthetic(64, 32, 3);
  for (float& v : synthetic.data) v = 0.05f;
  for (int c = 0; c < 3; ++c) synthetic.at(40, 5, c) = 2e4f;  // a one-texel sun, 28 degrees from the zenith
  write_exr(dir / "sun.exr", synthetic);
  std::vector<std::pair<std::string, std::filesystem::path>> maps = {{"synthetic sun", dir / "sun.exr"}};
  const char* shared = std::getenv("TWINRAY_SHARED");
  const std::filesystem::path studio =
      shared ? std::filesystem::path(shared) / "data/envmaps/studio_small_03_1k.hdr" : std::filesystem::path();
  if (shared && std::filesystem::exists(studio)) maps.push_back({"studio_small_03", studio});
  else out.note = "studio map skipped: $TWINRAY_SHARED/data/envmaps/studio_small_03_1k.hdr not found";
  for (const auto& [label, path] : maps) {
    Scene scene = base_scene({0.0f, 1.0f, 0.0f}, {0.0f, 0.0f, -1.0f}, 40.0f, image_size(options));
    const float rho = 0.5f;
    add_mesh(scene, quad({-100.0f, 0.0f, 100.0f}, {200.0f, 0.0f, 0.0f}, {0.0f, 0.0f, -200.0f}),
             add_material(scene, MaterialType::Diffuse, glm::vec3(rho)));
    scene.environment.type = EnvironmentType::Image;
    scene.environment.image = path;
    const auto env = EnvironmentLight::create(scene.environment);
    const Image img = read_image(path);
    const glm::dvec3 e = upper_hemisphere_irradiance(*env, img.width, img.height);
    const double expected = rho / std::numbers::pi * (e.x + e.y + e.z) / 3.0;
    parts.push_back({label, render_and_measure(scene, backend_name, spp_for(64, options),
                                               [&](int, int) { return expected; })});
  }
  std::filesystem::remove_all(dir);
  return finish(out, backend_name, parts);
}

// Grazing angles: a diffuse plane (albedo 0.5) under a uniform sky seen from 1 cm above, the top of the
// frame 0.5 degrees below the horizon, so camera rays meet the plane at 0.5 to 10.5 degrees and every
// bounce ray leaves a point that its own plane nearly contains: every pixel must be 0.5 exactly. And a
// tessellated albedo-1 sphere in the same sky, whose silhouette triangles are seen edge-on: every pixel 1.
// (twinray has no shading normals, so the geometric normal is the only one; see docs/stress.md.)
Outcome grazing(const std::string& backend_name, const StressOptions& options) {
  std::vector<std::pair<std::string, Measured>> parts;
  {
    const float vfov = 10.0f, down = (0.5f * vfov + 0.5f) * std::numbers::pi_v<float> / 180.0f;
    Scene scene = base_scene({0.0f, 0.01f, 0.0f}, {0.0f, 0.01f - std::tan(down), -1.0f}, vfov, image_size(options));
    scene.environment.type = EnvironmentType::Constant;
    scene.environment.radiance = glm::vec3(1.0f);
    add_mesh(scene, quad({-1000.0f, 0.0f, 1000.0f}, {2000.0f, 0.0f, 0.0f}, {0.0f, 0.0f, -2000.0f}),
             add_material(scene, MaterialType::Diffuse, glm::vec3(0.5f)));
    parts.push_back({"grazing plane", render_and_measure(scene, backend_name, spp_for(64, options),
                                                         [](int, int) { return 0.5; })});
  }
  {
    Scene scene = base_scene({0.0f, 0.0f, 3.0f}, {0.0f, 0.0f, 0.0f}, 40.0f, image_size(options));
    scene.environment.type = EnvironmentType::Constant;
    scene.environment.radiance = glm::vec3(1.0f);
    add_mesh(scene, tessellated_sphere({0, 0, 0}, 1.0f, 3).meshes.front(),
             add_material(scene, MaterialType::Diffuse, glm::vec3(1.0f)));
    parts.push_back({"mesh furnace albedo 1", render_and_measure(scene, backend_name, spp_for(32, options),
                                                                 [](int, int) { return 1.0; })});
  }
  return finish({}, backend_name, parts);
}

// A caustic: a glass sphere (ior 1.5) between a small bright light and a diffuse floor. The light is
// seen through the sphere only along specular chains that light sampling cannot build, so the focus is
// BSDF-sampled and noisy; what must hold is that no sample is NaN/Inf or negative and the image stays
// finite. The expected figure is the floor's direct light without the sphere (for scale only: the caustic
// redistributes light, so the mean is reported, not judged).
Outcome glass_caustic(const std::string& backend_name, const StressOptions& options) {
  Outcome out;
  Scene scene = base_scene({0.0f, 3.0f, 3.0f}, {0.0f, 0.0f, 0.0f}, 40.0f, image_size(options));
  add_mesh(scene, quad({-10.0f, 0.0f, 10.0f}, {20.0f, 0.0f, 0.0f}, {0.0f, 0.0f, -20.0f}),
           add_material(scene, MaterialType::Diffuse, glm::vec3(0.5f)));
  add_sphere(scene, {0.0f, 1.0f, 0.0f}, 0.5f, add_material(scene, MaterialType::Glass, glm::vec3(0.0f), 1.5f));
  add_sphere(scene, {0.0f, 3.0f, 0.0f}, 0.05f,
             add_material(scene, MaterialType::Emissive, glm::vec3(0.0f), 1.5f, glm::vec3(2000.0f)));
  Measured m = render_and_measure(scene, backend_name, spp_for(64, options), [](int, int) { return 0.0; });
  const bool ok = m.nonfinite == 0 && m.negative == 0 && std::isfinite(m.mean) && m.mean > 0.0;
  out.status = ok ? Status::Pass : Status::Fail;
  out.figures = fmt::format("caustic: mean {:.4g} (4se {:.2g}), {:.2f} s, NaN/Inf {}, neg {}", m.mean,
                            4.0 * m.standard_error, m.seconds, m.nonfinite, m.negative);
  out.json = to_json(m);
  set_requirement(out, backend_name, true, "");
  return out;
}

// The exact backend answers single rays for the arbiter at tens of microseconds each: rendering with it would
// take hours, and these cases test the integrator, which every backend shares.
StressCase not_for_exact(StressCase c) {
  c.run = [run = c.run](const std::string& backend_name, const StressOptions& options) {
    if (backend_name != "exact") return run(backend_name, options);
    Outcome out;
    out.status = Status::Skip;
    out.required = false;
    out.figures = "not rendered";
    out.note = "exact: an arbiter for single rays, too slow to render with";
    return out;
  };
  return c;
}

}  // namespace

void add_light_transport_cases(std::vector<StressCase>& cases) {
  const std::size_t first = cases.size();
  cases.push_back({"lt-furnace-long-paths", "light-transport",
                   "closed emissive furnace with albedo 0.9: L = Le / (1 - a), 10-segment average paths",
                   furnace_long_paths});
  cases.push_back({"lt-glass-furnace", "light-transport",
                   "glass spheres (ior 1.0001, 1.5, 4.0 with total internal reflection) in a uniform sky: L = sky",
                   glass_furnace});
  cases.push_back({"lt-tiny-bright-light", "light-transport",
                   "a 1e-3 light of radiance 1e6 over a floor (fireflies): analytic irradiance", tiny_bright_light});
  cases.push_back({"lt-env-small-sources", "light-transport",
                   "environment maps with tiny very bright texels over a floor: exact irradiance sum",
                   environment_small_sources});
  cases.push_back({"lt-grazing", "light-transport",
                   "a plane seen at 0.5-10.5 degrees and a tessellated furnace sphere: exact radiance", grazing});
  cases.push_back({"lt-glass-caustic", "light-transport",
                   "a caustic through a glass sphere from a small bright light: no NaN/Inf/negative samples",
                   glass_caustic});
  for (std::size_t k = first; k < cases.size(); ++k) cases[k] = not_for_exact(std::move(cases[k]));
}

}  // namespace twinray::stress
