#include "core/scene/mitsuba_export.h"

#include "core/image/image_io.h"
#include "core/util/atomic_file.h"
#include "core/util/input_error.h"

#include <fmt/core.h>
#include <glm/geometric.hpp>
#include <pugixml.hpp>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <sstream>
#include <system_error>
#include <set>

namespace twinray {
namespace {

static_assert(std::endian::native == std::endian::little, "the PLY writer emits the host's bytes as little-endian");

// Nine significant digits: every float survives the text round trip exactly.
std::string num(float v) { return fmt::format("{:.9g}", v); }
std::string vec(const glm::vec3& v) { return num(v.x) + ", " + num(v.y) + ", " + num(v.z); }

void add_value(pugi::xml_node parent, const char* tag, const char* name, const std::string& value) {
  pugi::xml_node n = parent.append_child(tag);
  n.append_attribute("name") = name;
  n.append_attribute("value") = value.c_str();
}

void add_rgb(pugi::xml_node parent, const char* name, const glm::vec3& c) { add_value(parent, "rgb", name, vec(c)); }

// A file name made of the shape's index and a readable form of its name.
std::string mesh_file_name(std::uint32_t geom_id, const std::string& name) {
  std::string clean;
  for (const char c : name) {
    const bool keep = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-' || c == '_';
    clean += keep ? c : '_';
  }
  if (clean.size() > 40) clean.resize(40);
  return fmt::format("meshes/{:03}-{}.ply", geom_id, clean.empty() ? "shape" : clean);
}

// Material names are unique within a scene (JSON object keys), so they serve as XML ids as they are; the
// importer reads them back as the materials' names.
// A procedural or resampled map is written as EXR under its name; a copied file keeps its name.
// How many times each texel is repeated in each direction: never for a bilinearly filtered map, which
// Mitsuba must see as it is.
int environment_upsample(const Environment& env, const MitsubaExportOptions& options) {
  return env.filter == EnvironmentFilter::Bilinear ? 1 : std::max(1, options.env_upsample);
}

std::string environment_file_name(const Environment& env, const MitsubaExportOptions& options) {
  std::filesystem::path name = env.image.filename();
  if (env.pixels || environment_upsample(env, options) > 1) name.replace_extension(".exr");
  return name.string();
}

// Every texel repeated k x k times (RGB of the first three channels, grey repeated).
Image upsampled(const Image& map, int k) {
  Image out(map.width * k, map.height * k, 3);
  for (int y = 0; y < out.height; ++y)
    for (int x = 0; x < out.width; ++x)
      for (int c = 0; c < 3; ++c) out.at(x, y, c) = map.at(x / k, y / k, std::min(c, map.channels - 1));
  return out;
}

std::string material_id(const Material& m) { return m.name; }

// The BSDF of a material; two-sided ones inside `twosided`.
void add_bsdf(pugi::xml_node scene_node, const Material& m) {
  pugi::xml_node outer = scene_node.append_child("bsdf");
  const bool wrap = m.type != MaterialType::Glass && m.two_sided;
  pugi::xml_node bsdf = outer;
  if (wrap) {
    outer.append_attribute("type") = "twosided";
    outer.append_attribute("id") = material_id(m).c_str();
    bsdf = outer.append_child("bsdf");
  } else {
    outer.append_attribute("id") = material_id(m).c_str();
  }
  switch (m.type) {
    case MaterialType::Diffuse:
      bsdf.prepend_attribute("type") = "diffuse";
      add_rgb(bsdf, "reflectance", m.albedo);
      break;
    case MaterialType::Emissive:
      bsdf.prepend_attribute("type") = "diffuse";
      add_rgb(bsdf, "reflectance", m.albedo);
      break;
    case MaterialType::Mirror:
      bsdf.prepend_attribute("type") = "conductor";
      add_value(bsdf, "string", "material", "none");
      add_rgb(bsdf, "specular_reflectance", m.reflectance);
      break;
    case MaterialType::Glass:
      bsdf.prepend_attribute("type") = "dielectric";
      add_value(bsdf, "float", "int_ior", num(m.ior));
      add_value(bsdf, "float", "ext_ior", "1");
      break;
  }
  // The material's name, for a reader of the XML (Mitsuba ignores comments).
}

struct GeometryRef {
  const TriangleMesh* mesh = nullptr;
  const Sphere* sphere = nullptr;
};

std::vector<GeometryRef> geometry_by_id(const Scene& scene) {
  std::vector<GeometryRef> refs(scene.shapes.size());
  for (const TriangleMesh& m : scene.geometry.meshes)
    if (m.geom_id < refs.size()) refs[m.geom_id].mesh = &m;
  for (const Sphere& s : scene.geometry.spheres)
    if (s.geom_id < refs.size()) refs[s.geom_id].sphere = &s;
  return refs;
}

pugi::xml_document build_document(const Scene& scene, const MitsubaExportOptions& options) {
  pugi::xml_document doc;
  doc.append_child(pugi::node_comment)
      .set_value(fmt::format(" Exported by twinray from {} (conventions: docs/mitsuba.md) ",
                             scene.source.filename().string())
                     .c_str());
  pugi::xml_node root = doc.append_child("scene");
  root.append_attribute("version") = "3.0.0";
  pugi::xml_node spp_default = root.append_child("default");
  spp_default.append_attribute("name") = "spp";
  spp_default.append_attribute("value") = scene.render.spp;

  pugi::xml_node integrator = root.append_child("integrator");
  integrator.append_attribute("type") = "path";
  add_value(integrator, "integer", "max_depth", std::to_string(scene.render.max_depth));
  add_value(integrator, "integer", "rr_depth", std::to_string(options.rr_depth.value_or(scene.render.rr_depth)));

  // Clip planes that clip nothing: twinray has none. The near plane stays well below any distance in the
  // scene, the far plane beyond its farthest point.
  const CameraDesc& cam = scene.camera;
  const Bounds3 bounds = scene.geometry.bounds();
  double far = 1e4;
  double extent = 1.0;
  if (!bounds.empty()) {
    extent = glm::length(glm::dvec3(bounds.hi) - glm::dvec3(bounds.lo));
    const glm::dvec3 c = 0.5 * (glm::dvec3(bounds.lo) + glm::dvec3(bounds.hi));
    far = std::max(far, 2.0 * (glm::length(c - glm::dvec3(cam.position)) + extent));
  }
  const double near = std::min(1e-2, 1e-3 * std::max(extent, 1e-30));

  pugi::xml_node sensor = root.append_child("sensor");
  sensor.append_attribute("type") = "perspective";
  add_value(sensor, "float", "fov", num(cam.vfov_deg));
  add_value(sensor, "string", "fov_axis", "y");
  add_value(sensor, "float", "near_clip", fmt::format("{:.9g}", near));
  add_value(sensor, "float", "far_clip", fmt::format("{:.9g}", far));
  pugi::xml_node lookat = sensor.append_child("transform");
  lookat.append_attribute("name") = "to_world";
  pugi::xml_node la = lookat.append_child("lookat");
  la.append_attribute("origin") = vec(cam.position).c_str();
  la.append_attribute("target") = vec(cam.look_at).c_str();
  la.append_attribute("up") = vec(cam.up).c_str();
  pugi::xml_node sampler = sensor.append_child("sampler");
  sampler.append_attribute("type") = "independent";
  add_value(sampler, "integer", "sample_count", "$spp");
  // Mitsuba's seed is a 32-bit integer: the low bits of twinray's 64-bit seed.
  add_value(sampler, "integer", "seed", std::to_string(scene.render.seed & 0x7fffffffu));
  pugi::xml_node film = sensor.append_child("film");
  film.append_attribute("type") = "hdrfilm";
  add_value(film, "integer", "width", std::to_string(cam.width));
  add_value(film, "integer", "height", std::to_string(cam.height));
  add_value(film, "string", "pixel_format", "rgb");
  film.append_child("rfilter").append_attribute("type") = "box";

  std::set<std::string> used_ids;
  for (const Material& m : scene.materials) {
    add_bsdf(root, m);
    used_ids.insert(material_id(m));
  }

  const std::vector<GeometryRef> geometry = geometry_by_id(scene);
  for (std::uint32_t id_number = 0; id_number < scene.shapes.size(); ++id_number) {
    const ShapeInfo& info = scene.shapes[id_number];
    const GeometryRef& g = geometry[id_number];
    if (g.mesh == nullptr && g.sphere == nullptr) continue;  // every triangle was degenerate: nothing to draw
    pugi::xml_node shape = root.append_child("shape");
    // Mitsuba's ids are global and unique: a shape whose name is taken (by a material or another shape)
    // gets its geometry id appended.
    std::string id = info.name;
    if (!used_ids.insert(id).second) {
      id = fmt::format("{}-{}", info.name, id_number);
      used_ids.insert(id);
    }
    shape.append_attribute("id") = id.c_str();
    if (g.sphere != nullptr) {
      shape.prepend_attribute("type") = "sphere";
      pugi::xml_node center = shape.append_child("point");
      center.append_attribute("name") = "center";
      center.append_attribute("value") = vec(g.sphere->center).c_str();
      add_value(shape, "float", "radius", num(g.sphere->radius));
    } else {
      shape.prepend_attribute("type") = "ply";
      add_value(shape, "string", "filename", mesh_file_name(id_number, info.name));
      add_value(shape, "boolean", "face_normals", "true");
    }
    const Material& m = scene.materials[info.material];
    shape.append_child("ref").append_attribute("id") = material_id(m).c_str();
    if (m.type == MaterialType::Emissive) {
      pugi::xml_node emitter = shape.append_child("emitter");
      emitter.append_attribute("type") = "area";
      add_rgb(emitter, "radiance", m.radiance);
    }
  }

  const Environment& env = scene.environment;
  if (env.type == EnvironmentType::Constant) {
    pugi::xml_node e = root.append_child("emitter");
    e.append_attribute("type") = "constant";
    add_rgb(e, "radiance", env.radiance);
  } else if (env.type == EnvironmentType::Image) {
    pugi::xml_node e = root.append_child("emitter");
    e.append_attribute("type") = "envmap";
    add_value(e, "string", "filename", "textures/" + environment_file_name(env, options));
    add_value(e, "float", "scale", num(env.scale));
    pugi::xml_node t = e.append_child("transform");
    t.append_attribute("name") = "to_world";
    pugi::xml_node r = t.append_child("rotate");
    r.append_attribute("y") = "1";
    r.append_attribute("angle") = fmt::format("{:.9g}", 180.0 + static_cast<double>(env.rotation_deg)).c_str();
  }
  return doc;
}

std::string to_text(const pugi::xml_document& doc) {
  std::ostringstream out;
  doc.save(out, "    ", pugi::format_default, pugi::encoding_utf8);
  return out.str();
}

}  // namespace

std::string ply_bytes(const TriangleMesh& mesh) {
  std::string out = fmt::format(
      "ply\nformat binary_little_endian 1.0\ncomment written by twinray\nelement vertex {}\nproperty float x\n"
      "property float y\nproperty float z\nelement face {}\nproperty list uchar uint vertex_indices\nend_header\n",
      mesh.positions.size(), mesh.indices.size());
  const std::size_t header = out.size();
  out.resize(header + mesh.positions.size() * 12 + mesh.indices.size() * 13);
  char* p = out.data() + header;
  for (const glm::vec3& v : mesh.positions) {
    std::memcpy(p, &v.x, 4);
    std::memcpy(p + 4, &v.y, 4);
    std::memcpy(p + 8, &v.z, 4);
    p += 12;
  }
  for (const glm::uvec3& t : mesh.indices) {
    *p++ = 3;
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t i = t[k];
      std::memcpy(p, &i, 4);
      p += 4;
    }
  }
  return out;
}

std::string mitsuba_scene_xml(const Scene& scene, const MitsubaExportOptions& options) {
  return to_text(build_document(scene, options));
}

std::filesystem::path export_mitsuba_scene(const Scene& scene, const std::filesystem::path& out_dir,
                                           const MitsubaExportOptions& options) {
  std::error_code ec;
  std::filesystem::create_directories(out_dir / "meshes", ec);
  if (ec) throw InputError(out_dir, "", "cannot create the folder: " + ec.message());
  const std::vector<GeometryRef> geometry = geometry_by_id(scene);
  for (std::uint32_t id = 0; id < scene.shapes.size(); ++id)
    if (geometry[id].mesh != nullptr)
      write_file_atomically(out_dir / mesh_file_name(id, scene.shapes[id].name), ply_bytes(*geometry[id].mesh));
  if (scene.environment.type == EnvironmentType::Image) {
    std::filesystem::create_directories(out_dir / "textures", ec);
    const std::filesystem::path target = out_dir / "textures" / environment_file_name(scene.environment, options);
    const int upsample = environment_upsample(scene.environment, options);
    if (scene.environment.pixels || upsample > 1) {
      const Image map = scene.environment.pixels ? *scene.environment.pixels : read_image(scene.environment.image);
      write_exr(target, upsampled(map, upsample));
    } else {
      std::filesystem::copy_file(scene.environment.image, target, std::filesystem::copy_options::overwrite_existing, ec);
      if (ec) throw InputError(scene.environment.image, "", "cannot copy the environment map to " + target.string() + ": " + ec.message());
    }
  }
  const std::filesystem::path xml = out_dir / "scene.xml";
  write_file_atomically(xml, mitsuba_scene_xml(scene, options));
  return xml;
}

}  // namespace twinray
