#include "harness/converge/reference_cache.h"

#include <fmt/core.h>

#include <cstdlib>
#include <cstring>
#include <fstream>
#include <span>
#include <type_traits>

namespace twinray::converge {

namespace {

class Fnv1a {
 public:
  void bytes(const void* data, std::size_t n) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < n; ++i) {
      h_ ^= p[i];
      h_ *= 0x100000001b3ull;
    }
  }
  template <class T>
  void value(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    bytes(&v, sizeof(T));
  }
  void text(const std::string& s) {
    value(s.size());
    bytes(s.data(), s.size());
  }
  template <class T>
  void array(std::span<const T> v) {
    value(v.size());
    bytes(v.data(), v.size_bytes());
  }
  void file(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    char buffer[1 << 16];
    while (in) {
      in.read(buffer, sizeof(buffer));
      bytes(buffer, static_cast<std::size_t>(in.gcount()));
    }
  }
  std::uint64_t digest() const { return h_; }

 private:
  std::uint64_t h_ = 0xcbf29ce484222325ull;
};

void hash_vec3(Fnv1a& h, const glm::vec3& v) {
  h.value(v.x);
  h.value(v.y);
  h.value(v.z);
}

}  // namespace

std::uint64_t reference_key(const Scene& scene, const ReferenceSettings& settings) {
  Fnv1a h;
  h.text(kReferenceVersion);
  const CameraDesc& cam = scene.camera;
  hash_vec3(h, cam.position);
  hash_vec3(h, cam.look_at);
  hash_vec3(h, cam.up);
  h.value(cam.vfov_deg);
  h.value(cam.width);
  h.value(cam.height);
  h.value(scene.materials.size());
  for (const Material& m : scene.materials) {
    h.value(static_cast<int>(m.type));
    hash_vec3(h, m.albedo);
    hash_vec3(h, m.reflectance);
    h.value(m.ior);
    hash_vec3(h, m.radiance);
  }
  h.value(scene.shapes.size());
  for (const ShapeInfo& s : scene.shapes) {
    h.value(static_cast<int>(s.kind));
    h.value(s.material);
  }
  h.value(scene.geometry.meshes.size());
  for (const TriangleMesh& m : scene.geometry.meshes) {
    h.value(m.geom_id);
    h.array(std::span<const glm::vec3>(m.positions));
    h.array(std::span<const glm::uvec3>(m.indices));
  }
  h.value(scene.geometry.spheres.size());
  for (const Sphere& s : scene.geometry.spheres) {
    h.value(s.geom_id);
    hash_vec3(h, s.center);
    h.value(s.radius);
  }
  const Environment& env = scene.environment;
  h.value(static_cast<int>(env.type));
  hash_vec3(h, env.radiance);
  h.value(env.rotation_deg);
  h.value(env.scale);
  h.value(static_cast<int>(env.filter));
  if (env.type == EnvironmentType::Image && env.pixels) h.array(std::span<const float>(env.pixels->data));
  else if (env.type == EnvironmentType::Image) h.file(env.image);
  h.value(settings.spp);
  h.value(settings.max_depth);
  h.value(settings.rr_depth);
  h.value(settings.seed);
  return h.digest();
}

std::string key_hex(std::uint64_t key) { return fmt::format("{:016x}", key); }

std::filesystem::path cache_directory() {
  auto env = [](const char* name) -> const char* {
    const char* v = std::getenv(name);
    return v && *v ? v : nullptr;
  };
  if (const char* dir = env("TWINRAY_CACHE_DIR")) return dir;
  if (const char* xdg = env("XDG_CACHE_HOME")) return std::filesystem::path(xdg) / "twinray";
  if (const char* home = env("HOME")) return std::filesystem::path(home) / ".cache" / "twinray";
  return ".twinray-cache";
}

std::filesystem::path cached_reference_path(const Scene& scene, const ReferenceSettings& settings) {
  return cache_directory() / "references" / (key_hex(reference_key(scene, settings)) + ".exr");
}

}  // namespace twinray::converge
