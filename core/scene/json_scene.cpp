#include "core/scene/json_scene.h"

#include "core/scene/geometry_cleanup.h"
#include "core/scene/input_file.h"
#include "core/scene/json_reader.h"
#include "core/scene/mesh_file.h"
#include "core/scene/shared_data.h"
#include "core/scene/transform.h"
#include "core/util/input_error.h"

#include <glm/geometric.hpp>

#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <unordered_map>

namespace twinray {
namespace {

// Largest image side: far beyond any real render, small enough that width * height * pixel data fits memory
// arithmetic without overflow.
constexpr std::int64_t kMaxImageSide = 65536;
// Per-pixel sample counts are accumulated and divided in float: integers up to 2^24 are exact in float.
constexpr std::int64_t kMaxSpp = std::int64_t{1} << 24;

class SceneParser {
 public:
  SceneParser(const std::filesystem::path& file, Scene& scene)
      : file_(file), base_dir_(file.parent_path()), scene_(scene) {}

  void parse(const JsonNode& root) {
    root.expect_object({"camera", "materials", "shapes", "environment", "render"});
    parse_camera(root.member("camera"));
    parse_materials(root.member("materials"));
    parse_shapes(root.member("shapes"));
    if (const auto env = root.optional_member("environment")) parse_environment(*env);
    if (const auto render = root.optional_member("render")) parse_render(*render);
    clean_geometry(scene_.geometry, scene_.report);
  }

 private:
  // ---- camera -------------------------------------------------------------------------------------------

  void parse_camera(const JsonNode& node) {
    node.expect_object({"position", "look_at", "up", "fov", "width", "height"});
    CameraDesc& camera = scene_.camera;
    camera.position = node.member("position").as_vec3();
    camera.look_at = node.member("look_at").as_vec3();
    if (const auto up = node.optional_member("up")) camera.up = up->as_vec3();
    const JsonNode fov = node.member("fov");
    camera.vfov_deg = fov.as_float();
    if (!(camera.vfov_deg > 0.0f && camera.vfov_deg < 180.0f))
      fov.fail("vertical field of view must be in (0, 180) degrees, got " + fov.json().dump());
    camera.width = static_cast<int>(node.member("width").as_integer(1, kMaxImageSide));
    camera.height = static_cast<int>(node.member("height").as_integer(1, kMaxImageSide));

    // Degenerate views would give the camera a NaN basis: reject them here, where the user can fix them.
    const glm::dvec3 view = glm::dvec3(camera.look_at) - glm::dvec3(camera.position);
    if (glm::length(view) == 0.0) node.member("look_at").fail("look_at must differ from position");
    const glm::dvec3 up = glm::dvec3(camera.up);
    if (glm::length(up) == 0.0) node.member("up").fail("up must be non-zero");
    // sin of the angle between view and up; 1e-6 rad is far below any intended camera tilt.
    if (glm::length(glm::cross(glm::normalize(view), glm::normalize(up))) < 1e-6)
      node.has("up") ? node.member("up").fail("up must not be parallel to the view direction")
                     : node.fail("the view direction is vertical: give an 'up' that is not parallel to it");
  }

  // ---- materials ----------------------------------------------------------------------------------------

  static glm::vec3 reflectance_color(const JsonNode& node) {
    const glm::vec3 c = node.as_color();
    // Reflecting more than arrives would create energy and make the path tracer diverge.
    if (c.x > 1.0f || c.y > 1.0f || c.z > 1.0f) node.fail("reflectance components must be at most 1");
    return c;
  }

  void parse_materials(const JsonNode& node) {
    if (!node.is_object()) node.fail("expected an object mapping material names to materials");
    for (const auto& [name, value] : node.json().items()) {
      if (name == "comment") continue;
      const JsonNode m = node.member(name);
      if (name.empty()) m.fail("material name must not be empty");
      Material material;
      material.name = name;
      const JsonNode type = m.member("type");
      const std::string type_name = type.as_string();
      if (type_name == "diffuse") {
        m.expect_object({"type", "albedo", "two_sided"});
        material.type = MaterialType::Diffuse;
        material.albedo = reflectance_color(m.member("albedo"));
      } else if (type_name == "mirror") {
        m.expect_object({"type", "reflectance", "two_sided"});
        material.type = MaterialType::Mirror;
        if (const auto r = m.optional_member("reflectance")) material.reflectance = reflectance_color(*r);
      } else if (type_name == "glass") {
        m.expect_object({"type", "ior"});
        material.type = MaterialType::Glass;
        if (const auto ior = m.optional_member("ior")) {
          material.ior = ior->as_float();
          if (!(material.ior > 0.0f)) ior->fail("ior must be positive, got " + ior->json().dump());
        }
      } else if (type_name == "emissive") {
        m.expect_object({"type", "radiance", "albedo", "two_sided"});
        material.type = MaterialType::Emissive;
        material.radiance = m.member("radiance").as_color();
        if (const auto albedo = m.optional_member("albedo")) material.albedo = reflectance_color(*albedo);
      } else {
        type.fail("unknown material type '" + type_name + "' (expected diffuse, mirror, glass or emissive)");
      }
      if (const auto sided = m.optional_member("two_sided")) material.two_sided = sided->as_bool();
      material_index_.emplace(name, static_cast<std::uint32_t>(scene_.materials.size()));
      scene_.materials.push_back(std::move(material));
    }
  }

  std::uint32_t material_reference(const JsonNode& node) const {
    const std::string name = node.as_string();
    const auto it = material_index_.find(name);
    if (it == material_index_.end()) {
      std::string known;
      for (const Material& m : scene_.materials) known += (known.empty() ? "" : ", ") + m.name;
      node.fail("unknown material '" + name + "' (defined: " + (known.empty() ? "none" : known) + ")");
    }
    return it->second;
  }

  // ---- transforms ---------------------------------------------------------------------------------------

  static AffineTransform parse_transform(const JsonNode& node) {
    if (node.has("matrix")) {
      node.expect_object({"matrix"});
      const JsonNode matrix = node.member("matrix");
      if (matrix.expect_array() != 16) matrix.fail("expected 16 numbers (a row-major 4x4 matrix)");
      double a[16];
      for (std::size_t i = 0; i < 16; ++i) a[i] = matrix.element(i).as_double();
      if (a[12] != 0.0 || a[13] != 0.0 || a[14] != 0.0 || a[15] != 1.0)
        matrix.fail("the last row must be 0 0 0 1 (only affine transforms are supported)");
      AffineTransform t;
      for (int row = 0; row < 3; ++row) {
        for (int col = 0; col < 3; ++col) t.linear[col][row] = a[4 * row + col];
        t.translation[row] = a[4 * row + 3];
      }
      if (!(std::abs(t.determinant()) > 0.0) || !std::isfinite(t.determinant()))
        matrix.fail("the matrix is singular (it would flatten the shape)");
      return t;
    }
    node.expect_object({"scale", "rotate", "translate"});
    glm::dvec3 scale(1.0), axis(0.0, 1.0, 0.0), translate(0.0);
    double angle = 0.0;
    if (const auto s = node.optional_member("scale")) {
      scale = s->json().is_number() ? glm::dvec3(s->as_double()) : s->as_dvec3();
      if (scale.x == 0.0 || scale.y == 0.0 || scale.z == 0.0) s->fail("scale factors must be non-zero");
    }
    if (const auto r = node.optional_member("rotate")) {
      r->expect_object({"axis", "angle"});
      axis = r->member("axis").as_dvec3();
      if (glm::length(axis) == 0.0) r->member("axis").fail("rotation axis must be non-zero");
      angle = r->member("angle").as_double();
    }
    if (const auto t = node.optional_member("translate")) translate = t->as_dvec3();
    return AffineTransform::scale_rotate_translate(scale, axis, angle, translate);
  }

  // ---- shapes -------------------------------------------------------------------------------------------

  void parse_shapes(const JsonNode& node) {
    const std::size_t count = node.expect_array();
    if (count > std::numeric_limits<std::uint32_t>::max()) node.fail("too many shapes");
    for (std::size_t i = 0; i < count; ++i) parse_shape(node.element(i), static_cast<std::uint32_t>(i));
  }

  void parse_shape(const JsonNode& node, std::uint32_t geom_id) {
    const JsonNode type = node.member("type");
    const std::string type_name = type.as_string();
    ShapeInfo shape;
    if (type_name == "mesh") {
      node.expect_object({"type", "file", "material", "name", "transform"});
      shape.kind = ShapeKind::Mesh;
      const JsonNode file = node.member("file");
      shape.file = resolve_file(file);
      TriangleMesh mesh = read_referenced_mesh(shape.file, file);
      finish_mesh(node, geom_id, std::move(mesh));
    } else if (type_name == "triangles") {
      node.expect_object({"type", "positions", "indices", "material", "name", "transform"});
      shape.kind = ShapeKind::Mesh;
      finish_mesh(node, geom_id, parse_inline_triangles(node));
    } else if (type_name == "sphere") {
      node.expect_object({"type", "center", "radius", "material", "name", "transform"});
      shape.kind = ShapeKind::Sphere;
      parse_sphere(node, geom_id);
    } else {
      type.fail("unknown shape type '" + type_name + "' (expected mesh, triangles or sphere)");
    }
    shape.material = material_reference(node.member("material"));
    if (const auto name = node.optional_member("name")) shape.name = name->as_string();
    else shape.name = "shape " + std::to_string(geom_id);
    scene_.shapes.push_back(std::move(shape));
  }

  TriangleMesh read_referenced_mesh(const std::filesystem::path& path, const JsonNode& file_node) {
    try {
      return read_mesh_file(path, scene_.report);
    } catch (const InputError& e) {
      // Keep the mesh file's own location (its line) and say which scene entry pulled it in.
      throw InputError(e.file(), e.where(),
                       e.message() + " (mesh referenced at " + file_node.pointer() + " in " + file_.string() + ")");
    }
  }

  TriangleMesh parse_inline_triangles(const JsonNode& node) const {
    TriangleMesh mesh;
    const JsonNode positions = node.member("positions");
    const std::size_t n = positions.expect_array();
    if (n > std::numeric_limits<std::uint32_t>::max()) positions.fail("too many positions");
    mesh.positions.reserve(n + 1);
    for (std::size_t i = 0; i < n; ++i) mesh.positions.push_back(positions.element(i).as_vec3());
    const JsonNode indices = node.member("indices");
    const std::size_t t = indices.expect_array();
    mesh.indices.reserve(t);
    for (std::size_t i = 0; i < t; ++i) {
      const JsonNode tri = indices.element(i);
      tri.expect_array_of_size(3);
      glm::uvec3 v;
      for (std::size_t k = 0; k < 3; ++k) {
        const JsonNode index = tri.element(k);
        const std::int64_t value =
            index.as_integer(std::numeric_limits<std::int64_t>::min(), std::numeric_limits<std::int64_t>::max());
        if (value < 0 || static_cast<std::uint64_t>(value) >= n)
          index.fail("index " + index.json().dump() + " out of range (the shape has " + std::to_string(n) +
                     " positions)");
        v[static_cast<int>(k)] = static_cast<std::uint32_t>(value);
      }
      mesh.indices.push_back(v);
    }
    return mesh;
  }

  void finish_mesh(const JsonNode& node, std::uint32_t geom_id, TriangleMesh mesh) {
    mesh.geom_id = geom_id;
    if (const auto t = node.optional_member("transform")) {
      transform_mesh(mesh, parse_transform(*t));
      for (const glm::vec3& p : mesh.positions)
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
          t->fail("the transform moves vertices out of float range");
    }
    scene_.geometry.meshes.push_back(std::move(mesh));
  }

  void parse_sphere(const JsonNode& node, std::uint32_t geom_id) {
    Sphere sphere;
    sphere.geom_id = geom_id;
    sphere.center = node.member("center").as_vec3();
    const JsonNode radius = node.member("radius");
    sphere.radius = radius.as_float();
    if (!(sphere.radius > 0.0f)) radius.fail("radius must be positive, got " + radius.json().dump());
    if (const auto t = node.optional_member("transform")) {
      try {
        transform_sphere(sphere, parse_transform(*t));
      } catch (const std::invalid_argument& e) {
        t->fail(e.what());
      }
      const glm::vec3 c = sphere.center;
      if (!std::isfinite(c.x) || !std::isfinite(c.y) || !std::isfinite(c.z) || !std::isfinite(sphere.radius) ||
          !(sphere.radius > 0.0f))
        t->fail("the transform moves the sphere out of float range");
    }
    scene_.geometry.spheres.push_back(sphere);
  }

  // ---- environment and render settings ------------------------------------------------------------------

  void parse_environment(const JsonNode& node) {
    const JsonNode type = node.member("type");
    const std::string type_name = type.as_string();
    Environment& env = scene_.environment;
    if (type_name == "constant") {
      node.expect_object({"type", "radiance"});
      env.type = EnvironmentType::Constant;
      env.radiance = node.member("radiance").as_color();
    } else if (type_name == "image") {
      node.expect_object({"type", "file", "rotation", "scale", "filter"});
      env.type = EnvironmentType::Image;
      const JsonNode file = node.member("file");
      env.image = resolve_file(file);
      try {
        require_regular_file(env.image);
      } catch (const InputError& e) {
        throw InputError(e.file(), e.where(),
                         e.message() + " (environment image referenced at " + file.pointer() + " in " +
                             file_.string() + ")");
      }
      if (const auto r = node.optional_member("rotation")) env.rotation_deg = r->as_float();
      if (const auto s = node.optional_member("scale")) {
        env.scale = s->as_float();
        if (env.scale < 0.0f) s->fail("scale must be non-negative, got " + s->json().dump());
      }
      if (const auto f = node.optional_member("filter")) {
        const std::string filter = f->as_string();
        if (filter == "nearest") env.filter = EnvironmentFilter::Nearest;
        else if (filter == "bilinear") env.filter = EnvironmentFilter::Bilinear;
        else f->fail("unknown environment filter '" + filter + "' (expected nearest or bilinear)");
      }
    } else {
      type.fail("unknown environment type '" + type_name + "' (expected constant or image)");
    }
  }

  void parse_render(const JsonNode& node) {
    node.expect_object({"spp", "max_depth", "rr_depth", "seed"});
    RenderSettings& r = scene_.render;
    if (const auto spp = node.optional_member("spp")) r.spp = static_cast<int>(spp->as_integer(1, kMaxSpp));
    if (const auto depth = node.optional_member("max_depth")) {
      r.max_depth = static_cast<int>(depth->as_integer(-1, std::numeric_limits<int>::max()));
      if (r.max_depth == 0) depth->fail("max_depth must be -1 (unlimited) or at least 1, got 0");
    }
    if (const auto rr = node.optional_member("rr_depth"))
      r.rr_depth = static_cast<int>(rr->as_integer(1, std::numeric_limits<int>::max()));
    if (const auto seed = node.optional_member("seed")) r.seed = seed->as_unsigned();
  }

  // A file a scene names: relative to the scene's folder, absolute as it is, or in the shared data folder
  // when it starts with $TWINRAY_SHARED/ (core/scene/shared_data.h).
  std::filesystem::path resolve_file(const JsonNode& node) const {
    const std::string text = node.as_string();
    for (const std::string_view prefix : kSharedDataPrefixes) {
      if (!text.starts_with(prefix)) continue;
      const std::optional<std::filesystem::path> shared = find_shared_data(base_dir_);
      if (!shared)
        node.fail("'" + text + "' is in the shared data folder, which was not found: set TWINRAY_SHARED to it "
                  "(the folder with data/meshes), or place it as 'shared' beside the repository");
      return *shared / text.substr(prefix.size());
    }
    return resolve_relative(base_dir_, text);
  }

  const std::filesystem::path& file_;
  std::filesystem::path base_dir_;
  Scene& scene_;
  std::unordered_map<std::string, std::uint32_t> material_index_;
};

}  // namespace

Scene parse_json_scene(std::string_view text, const std::filesystem::path& scene_file) {
  const Json document = parse_json_text(text, scene_file);
  Scene scene;
  scene.source = scene_file;
  scene.from_bare_mesh = false;
  SceneParser(scene_file, scene).parse(JsonNode(document, "", scene_file));
  return scene;
}

Scene load_json_scene(const std::filesystem::path& scene_file) {
  const std::string text = read_input_file(scene_file);
  return parse_json_scene(text, scene_file);
}

}  // namespace twinray
