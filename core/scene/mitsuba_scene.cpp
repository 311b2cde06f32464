#include "core/scene/mitsuba_scene.h"

#include "core/scene/geometry_cleanup.h"
#include "core/scene/input_file.h"
#include "core/scene/mesh_file.h"
#include "core/scene/obj_reader.h"
#include "core/scene/ply_reader.h"
#include "core/scene/transform.h"
#include "core/util/input_error.h"

#include <fmt/core.h>
#include <glm/geometric.hpp>
#include <glm/mat4x4.hpp>
#include <glm/matrix.hpp>
#include <pugixml.hpp>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace twinray {
namespace {

constexpr int kMaxImageSide = 65536;  // as for JSON scenes
constexpr int kMaxSpp = 1 << 24;

// Mitsuba's named indices of refraction (its documentation's table: physical constants at 20 C, 589 nm).
const std::map<std::string, double, std::less<>> kNamedIor = {
    {"vacuum", 1.0},          {"helium", 1.000036},      {"hydrogen", 1.000132},  {"air", 1.000277},
    {"carbon dioxide", 1.00045}, {"water", 1.3330},      {"acetone", 1.36},       {"ethanol", 1.361},
    {"carbon tetrachloride", 1.461}, {"glycerol", 1.4729}, {"benzene", 1.501},    {"silicone oil", 1.52045},
    {"bromine", 1.661},       {"water ice", 1.31},       {"fused quartz", 1.458}, {"pyrex", 1.470},
    {"acrylic glass", 1.49},  {"polypropylene", 1.49},   {"bk7", 1.5046},         {"sodium chloride", 1.544},
    {"amber", 1.55},          {"pet", 1.5750},           {"diamond", 2.419}};

// Byte offset -> line number, for pugixml's offset_debug().
class LineIndex {
 public:
  explicit LineIndex(std::string_view text) {
    starts_.push_back(0);
    for (std::size_t i = 0; i < text.size(); ++i)
      if (text[i] == '\n') starts_.push_back(static_cast<std::ptrdiff_t>(i + 1));
  }
  int line_of(std::ptrdiff_t offset) const {
    if (offset < 0) return 0;
    return static_cast<int>(std::upper_bound(starts_.begin(), starts_.end(), offset) - starts_.begin());
  }

 private:
  std::vector<std::ptrdiff_t> starts_;
};

struct BsdfDesc {
  enum class Kind { Diffuse, Conductor, Dielectric } kind = Kind::Diffuse;
  bool two_sided = false;
  glm::vec3 color{0.5f};  // diffuse reflectance or conductor specular_reflectance
  float ior = 1.5f;       // int_ior / ext_ior
  std::string name;       // id, or "bsdf at line N"
};

class MitsubaParser {
 public:
  MitsubaParser(std::string_view text, const std::filesystem::path& file, Scene& scene)
      : text_(text), lines_(text), file_(file), base_dir_(file.parent_path()), scene_(scene) {}

  void parse() {
    pugi::xml_document doc;
    const pugi::xml_parse_result result =
        doc.load_buffer(text_.data(), text_.size(), pugi::parse_default, pugi::encoding_utf8);
    if (!result)
      throw InputError(file_, fmt::format("line {}", std::max(1, lines_.line_of(result.offset))),
                       std::string("XML syntax error: ") + result.description());
    const pugi::xml_node root = doc.document_element();
    if (std::string_view(root.name()) != "scene")
      fail(root, fmt::format("expected <scene> as the root element, found <{}>", root.name()));
    check_version(root);
    for (const pugi::xml_node& child : root.children())
      if (child.type() == pugi::node_element && std::string_view(child.name()) == "default") parse_default(child);
    for (const pugi::xml_node& child : root.children()) {
      if (child.type() != pugi::node_element) continue;
      const std::string_view tag = child.name();
      if (tag == "default") continue;
      if (tag == "integrator") parse_integrator(child);
      else if (tag == "sensor") parse_sensor(child);
      else if (tag == "bsdf") parse_top_level_bsdf(child);
      else if (tag == "shape") parse_shape(child);
      else if (tag == "emitter") parse_environment(child);
      else fail(child, fmt::format("<{}> is not supported by twinray's Mitsuba importer (docs/mitsuba.md lists the subset)", tag));
    }
    if (!sensor_seen_) fail(root, "the scene has no <sensor>: twinray needs a perspective camera");
    clean_geometry(scene_.geometry, scene_.report);
    check_clip_planes();
  }

 private:
  // ---- errors and attributes ----------------------------------------------------------------------------

  [[noreturn]] void fail(const pugi::xml_node& node, const std::string& message) const {
    throw InputError(file_, fmt::format("line {}", std::max(1, lines_.line_of(node.offset_debug()))), message);
  }

  std::string describe(const pugi::xml_node& node) const {
    // fmt rather than operator+: GCC 12 warns falsely (-Wstringop-overflow) on the concatenation.
    const pugi::xml_attribute type = node.attribute("type"), name = node.attribute("name");
    return fmt::format("<{}{}{}>", node.name(), type ? fmt::format(" type=\"{}\"", type.value()) : std::string(),
                       name ? fmt::format(" name=\"{}\"", name.value()) : std::string());
  }

  // An attribute's value with $parameters substituted; required unless `fallback` is given.
  std::string attr(const pugi::xml_node& node, const char* name, const char* fallback = nullptr) const {
    const pugi::xml_attribute a = node.attribute(name);
    if (!a) {
      if (fallback) return fallback;
      fail(node, fmt::format("{} needs the attribute '{}'", describe(node), name));
    }
    return substitute(node, a.value());
  }

  std::string substitute(const pugi::xml_node& node, std::string value) const {
    std::string out;
    for (std::size_t i = 0; i < value.size();) {
      if (value[i] != '$') {
        out += value[i++];
        continue;
      }
      std::size_t j = i + 1;
      while (j < value.size() && (std::isalnum(static_cast<unsigned char>(value[j])) || value[j] == '_')) ++j;
      const std::string key = value.substr(i + 1, j - i - 1);
      const auto it = defaults_.find(key);
      if (key.empty() || it == defaults_.end())
        fail(node, fmt::format("'${}' is not defined (add <default name=\"{}\" value=\"...\"/>)", key, key));
      out += it->second;
      i = j;
    }
    return out;
  }

  void check_version(const pugi::xml_node& root) const {
    const std::string version = attr(root, "version");
    int major = -1;
    std::from_chars(version.data(), version.data() + version.size(), major);
    if (major != 2 && major != 3)
      fail(root, fmt::format("scene version '{}' is not supported: twinray reads Mitsuba 2 and 3 scenes (version "
                             "2.x or 3.x); upgrade older files with Mitsuba 3 first", version));
  }

  void parse_default(const pugi::xml_node& node) {
    expect_attributes(node, {"name", "value"});
    const std::string name = node.attribute("name").value();
    if (name.empty()) fail(node, "<default> needs a non-empty 'name'");
    if (!node.attribute("value")) fail(node, "<default> needs a 'value'");
    defaults_.emplace(name, node.attribute("value").value());  // the first definition wins, as in Mitsuba
  }

  void expect_attributes(const pugi::xml_node& node, std::initializer_list<std::string_view> allowed) const {
    for (const pugi::xml_attribute& a : node.attributes())
      if (std::find(allowed.begin(), allowed.end(), std::string_view(a.name())) == allowed.end())
        fail(node, fmt::format("{}: attribute '{}' is not supported", describe(node), a.name()));
  }

  // ---- numbers ------------------------------------------------------------------------------------------

  std::vector<double> numbers(const pugi::xml_node& node, const std::string& text) const {
    std::vector<double> out;
    const char* p = text.data();
    const char* end = p + text.size();
    while (p < end) {
      while (p < end && (*p == ',' || std::isspace(static_cast<unsigned char>(*p)))) ++p;
      if (p == end) break;
      double v = 0.0;
      const auto [next, ec] = std::from_chars(p, end, v);
      if (ec != std::errc() || next == p)
        fail(node, fmt::format("{}: '{}' is not a list of numbers", describe(node), text));
      if (!std::isfinite(v) || std::abs(v) > static_cast<double>(std::numeric_limits<float>::max()))
        fail(node, fmt::format("{}: {} is not a finite 32-bit float", describe(node), text));
      out.push_back(v);
      p = next;
    }
    return out;
  }

  double number(const pugi::xml_node& node, const std::string& text) const {
    const std::vector<double> v = numbers(node, text);
    if (v.size() != 1) fail(node, fmt::format("{}: expected one number, got '{}'", describe(node), text));
    return v[0];
  }

  glm::dvec3 triple(const pugi::xml_node& node, const std::string& text) const {
    const std::vector<double> v = numbers(node, text);
    if (v.size() != 3) fail(node, fmt::format("{}: expected three numbers, got '{}'", describe(node), text));
    return {v[0], v[1], v[2]};
  }

  // ---- properties of an object ----------------------------------------------------------------------------

  // The named value children of an object, consumed one by one; whatever is left is an error (Mitsuba's own
  // "unreferenced property" rule, so a setting twinray would ignore is never silently dropped).
  class Properties {
   public:
    Properties(const MitsubaParser& p, const pugi::xml_node& object) : parser_(p), object_(object) {
      for (const pugi::xml_node& child : object.children()) {
        if (child.type() != pugi::node_element) continue;
        const std::string_view tag = child.name();
        if (tag == "float" || tag == "integer" || tag == "boolean" || tag == "string" || tag == "rgb" ||
            tag == "spectrum" || tag == "point" || tag == "vector" || tag == "transform") {
          const std::string name = parser_.attr(child, "name");
          if (!values_.emplace(name, child).second)
            parser_.fail(child, fmt::format("{}: property '{}' is given twice", parser_.describe(object), name));
        }
      }
    }

    std::optional<pugi::xml_node> take(const std::string& name, std::initializer_list<std::string_view> tags) {
      const auto it = values_.find(name);
      if (it == values_.end()) return std::nullopt;
      const pugi::xml_node node = it->second;
      values_.erase(it);
      if (std::find(tags.begin(), tags.end(), std::string_view(node.name())) == tags.end())
        parser_.fail(node, fmt::format("{}: property '{}' must be a {}, not <{}>", parser_.describe(object_), name,
                                       *tags.begin(), node.name()));
      return node;
    }

    std::optional<double> number(const std::string& name) {
      const auto n = take(name, {"float", "integer"});
      if (!n) return std::nullopt;
      parser_.expect_attributes(*n, {"name", "value"});
      return parser_.number(*n, parser_.attr(*n, "value"));
    }
    std::optional<int> integer(const std::string& name, int lo, int hi) {
      const auto n = take(name, {"integer"});
      if (!n) return std::nullopt;
      parser_.expect_attributes(*n, {"name", "value"});
      const std::string text = parser_.attr(*n, "value");
      long long v = 0;
      const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
      if (ec != std::errc() || end != text.data() + text.size() || v < lo || v > hi)
        parser_.fail(*n, fmt::format("{}: '{}' must be an integer in [{}, {}], got '{}'", parser_.describe(object_), name,
                                     lo, hi, text));
      return static_cast<int>(v);
    }
    std::optional<bool> boolean(const std::string& name) {
      const auto n = take(name, {"boolean"});
      if (!n) return std::nullopt;
      parser_.expect_attributes(*n, {"name", "value"});
      const std::string text = parser_.attr(*n, "value");
      if (text == "true") return true;
      if (text == "false") return false;
      parser_.fail(*n, fmt::format("'{}' must be true or false, got '{}'", name, text));
    }
    std::optional<std::string> string(const std::string& name) {
      const auto n = take(name, {"string"});
      if (!n) return std::nullopt;
      parser_.expect_attributes(*n, {"name", "value"});
      return parser_.attr(*n, "value");
    }
    std::optional<glm::dvec3> point(const std::string& name) {
      const auto n = take(name, {"point", "vector"});
      if (!n) return std::nullopt;
      parser_.expect_attributes(*n, {"name", "value", "x", "y", "z"});
      if (n->attribute("value")) return parser_.triple(*n, parser_.attr(*n, "value"));
      return glm::dvec3(parser_.number(*n, parser_.attr(*n, "x", "0")), parser_.number(*n, parser_.attr(*n, "y", "0")),
                        parser_.number(*n, parser_.attr(*n, "z", "0")));
    }
    // rgb (one or three values), float, or spectrum with a single constant value; non-negative.
    std::optional<glm::vec3> color(const std::string& name) {
      const auto n = take(name, {"rgb", "float", "spectrum"});
      if (!n) return std::nullopt;
      parser_.expect_attributes(*n, {"name", "value"});
      const std::string text = parser_.attr(*n, "value");
      if (std::string_view(n->name()) == "spectrum" && text.find(':') != std::string::npos)
        parser_.fail(*n, "a spectrum given by wavelengths is not supported: give an rgb value");
      const std::vector<double> v = parser_.numbers(*n, text);
      if (v.size() != 1 && !(v.size() == 3 && std::string_view(n->name()) == "rgb"))
        parser_.fail(*n, fmt::format("{}: expected one number{}, got '{}'", parser_.describe(*n),
                                     std::string_view(n->name()) == "rgb" ? " or three" : "", text));
      const glm::vec3 c = v.size() == 1 ? glm::vec3(static_cast<float>(v[0]))
                                        : glm::vec3(static_cast<float>(v[0]), static_cast<float>(v[1]), static_cast<float>(v[2]));
      if (c.x < 0.0f || c.y < 0.0f || c.z < 0.0f) parser_.fail(*n, "colour components must be non-negative");
      return c;
    }
    std::optional<glm::vec3> reflectance(const std::string& name) {
      const std::optional<glm::vec3> c = color(name);
      if (c && (c->x > 1.0f || c->y > 1.0f || c->z > 1.0f))
        parser_.fail(object_, fmt::format("{}: '{}' components must be at most 1", parser_.describe(object_), name));
      return c;
    }
    std::optional<glm::dmat4> transform(const std::string& name) {
      const auto n = take(name, {"transform"});
      if (!n) return std::nullopt;
      return parser_.parse_transform(*n);
    }

    // Every property not taken is an error, as is any child element `allowed_children` does not name.
    void finish(std::initializer_list<std::string_view> allowed_children = {}) const {
      if (!values_.empty()) {
        const pugi::xml_node n = values_.begin()->second;
        parser_.fail(n, fmt::format("{}: property '{}' is not supported by twinray", parser_.describe(object_),
                                    values_.begin()->first));
      }
      for (const pugi::xml_node& child : object_.children()) {
        if (child.type() != pugi::node_element) continue;
        const std::string_view tag = child.name();
        const bool value = tag == "float" || tag == "integer" || tag == "boolean" || tag == "string" || tag == "rgb" ||
                           tag == "spectrum" || tag == "point" || tag == "vector" || tag == "transform";
        if (!value && std::find(allowed_children.begin(), allowed_children.end(), tag) == allowed_children.end())
          parser_.fail(child, fmt::format("{} inside {} is not supported by twinray", parser_.describe(child),
                                          parser_.describe(object_)));
      }
    }

   private:
    const MitsubaParser& parser_;
    pugi::xml_node object_;
    std::map<std::string, pugi::xml_node> values_;
  };

  // ---- transforms ---------------------------------------------------------------------------------------

  glm::dmat4 parse_transform(const pugi::xml_node& node) const {
    glm::dmat4 m(1.0);
    for (const pugi::xml_node& op : node.children()) {
      if (op.type() != pugi::node_element) continue;
      const std::string_view tag = op.name();
      glm::dmat4 t(1.0);
      if (tag == "translate") {
        expect_attributes(op, {"value", "x", "y", "z"});
        const glm::dvec3 v = op.attribute("value") ? triple(op, attr(op, "value"))
                                                   : glm::dvec3(number(op, attr(op, "x", "0")), number(op, attr(op, "y", "0")),
                                                                number(op, attr(op, "z", "0")));
        t[3] = glm::dvec4(v, 1.0);
      } else if (tag == "scale") {
        expect_attributes(op, {"value", "x", "y", "z"});
        glm::dvec3 s(1.0);
        if (op.attribute("value")) {
          const std::vector<double> v = numbers(op, attr(op, "value"));
          if (v.size() == 1) s = glm::dvec3(v[0]);
          else if (v.size() == 3) s = glm::dvec3(v[0], v[1], v[2]);
          else fail(op, "<scale value> needs one or three numbers");
        } else {
          s = glm::dvec3(number(op, attr(op, "x", "1")), number(op, attr(op, "y", "1")), number(op, attr(op, "z", "1")));
        }
        if (s.x == 0.0 || s.y == 0.0 || s.z == 0.0) fail(op, "scale factors must be non-zero");
        t[0][0] = s.x;
        t[1][1] = s.y;
        t[2][2] = s.z;
      } else if (tag == "rotate") {
        expect_attributes(op, {"value", "x", "y", "z", "angle"});
        const glm::dvec3 axis = op.attribute("value") ? triple(op, attr(op, "value"))
                                                      : glm::dvec3(number(op, attr(op, "x", "0")), number(op, attr(op, "y", "0")),
                                                                   number(op, attr(op, "z", "0")));
        if (glm::length(axis) == 0.0) fail(op, "the rotation axis must be non-zero");
        const AffineTransform r =
            AffineTransform::scale_rotate_translate(glm::dvec3(1.0), axis, number(op, attr(op, "angle")), glm::dvec3(0.0));
        t = glm::dmat4(r.linear);
      } else if (tag == "matrix") {
        expect_attributes(op, {"value"});
        const std::vector<double> v = numbers(op, attr(op, "value"));
        if (v.size() != 16) fail(op, "<matrix value> needs 16 numbers (row-major 4x4)");
        if (v[12] != 0.0 || v[13] != 0.0 || v[14] != 0.0 || v[15] != 1.0)
          fail(op, "the matrix's last row must be 0 0 0 1 (only affine transforms are supported)");
        for (int row = 0; row < 4; ++row)
          for (int col = 0; col < 4; ++col) t[col][row] = v[static_cast<std::size_t>(4 * row + col)];
      } else if (tag == "lookat") {
        expect_attributes(op, {"origin", "target", "up"});
        const glm::dvec3 origin = triple(op, attr(op, "origin")), target = triple(op, attr(op, "target"));
        const glm::dvec3 up = triple(op, attr(op, "up"));
        const glm::dvec3 dir = target - origin;
        if (glm::length(dir) == 0.0) fail(op, "lookat: target must differ from origin");
        const glm::dvec3 d = glm::normalize(dir);
        const glm::dvec3 left_raw = glm::cross(up, d);
        if (!(glm::length(left_raw) > 1e-9)) fail(op, "lookat: up must not be parallel to the view direction");
        const glm::dvec3 left = glm::normalize(left_raw);
        const glm::dvec3 new_up = glm::cross(d, left);
        t[0] = glm::dvec4(left, 0.0);
        t[1] = glm::dvec4(new_up, 0.0);
        t[2] = glm::dvec4(d, 0.0);
        t[3] = glm::dvec4(origin, 1.0);
      } else {
        fail(op, fmt::format("<{}> inside <transform> is not supported (translate, rotate, scale, matrix, lookat)", tag));
      }
      m = t * m;
    }
    const double det = glm::determinant(glm::dmat3(m));
    if (!(std::abs(det) > 0.0) || !std::isfinite(det)) fail(node, "the transform is singular or not finite");
    return m;
  }

  static AffineTransform affine(const glm::dmat4& m) {
    AffineTransform t;
    t.linear = glm::dmat3(m);
    t.translation = glm::dvec3(m[3]);
    return t;
  }

  // ---- integrator and sensor ----------------------------------------------------------------------------

  void parse_integrator(const pugi::xml_node& node) {
    expect_attributes(node, {"type", "id", "name"});
    if (integrator_seen_) fail(node, "a second <integrator>");
    integrator_seen_ = true;
    const std::string type = attr(node, "type");
    if (type != "path")
      fail(node, fmt::format("integrator '{}' is not supported: twinray renders with a path tracer (type \"path\")", type));
    Properties p(*this, node);
    if (const auto d = p.integer("max_depth", -1, std::numeric_limits<int>::max())) {
      if (*d == 0) fail(node, "max_depth 0 renders nothing: use -1 (unlimited) or at least 1");
      scene_.render.max_depth = *d;
    }
    if (const auto d = p.integer("rr_depth", 1, std::numeric_limits<int>::max())) scene_.render.rr_depth = *d;
    if (const auto hide = p.boolean("hide_emitters"); hide && *hide)
      fail(node, "hide_emitters is not supported: twinray always shows emitters seen directly");
    p.finish();
  }

  void parse_sensor(const pugi::xml_node& node) {
    expect_attributes(node, {"type", "id", "name"});
    if (sensor_seen_) fail(node, "a second <sensor>: twinray renders one camera");
    sensor_seen_ = true;
    const std::string type = attr(node, "type");
    if (type != "perspective") fail(node, fmt::format("sensor '{}' is not supported (perspective only)", type));
    Properties p(*this, node);
    const double fov = p.number("fov").value_or(45.0);
    const std::string axis = p.string("fov_axis").value_or("x");
    if (!(fov > 0.0 && fov < 180.0)) fail(node, "fov must be in (0, 180) degrees");
    const glm::dmat4 to_world = p.transform("to_world").value_or(glm::dmat4(1.0));
    near_clip_ = p.number("near_clip").value_or(1e-2);
    far_clip_ = p.number("far_clip").value_or(1e4);
    clip_node_ = node;
    if (near_clip_ > 1e-2) fail(node, "near_clip above 0.01 would clip geometry, and twinray has no clip planes");
    for (const char* offset : {"principal_point_offset_x", "principal_point_offset_y"})
      if (const auto v = p.number(offset); v && *v != 0.0) fail(node, std::string(offset) + " is not supported");
    p.finish({"sampler", "film"});

    bool film_seen = false;
    for (const pugi::xml_node& child : node.children()) {
      if (child.type() != pugi::node_element) continue;
      if (std::string_view(child.name()) == "sampler") parse_sampler(child);
      else if (std::string_view(child.name()) == "film") {
        parse_film(child);
        film_seen = true;
      }
    }
    if (!film_seen) fail(node, "the sensor has no <film>: Mitsuba's default film filters with a Gaussian, twinray with a box; give <film type=\"hdrfilm\"> with <rfilter type=\"box\"/>");

    CameraDesc& cam = scene_.camera;
    const double w = cam.width, h = cam.height;
    const double t = std::tan(0.5 * fov * std::numbers::pi / 180.0);
    double tan_half_v = t;
    if (axis == "x" || (axis == "smaller" && w <= h) || (axis == "larger" && w > h)) tan_half_v = t * h / w;
    else if (axis == "diagonal") tan_half_v = t * h / std::sqrt(w * w + h * h);
    else if (axis != "y" && axis != "smaller" && axis != "larger")
      fail(node, fmt::format("fov_axis '{}' is not one of x, y, smaller, larger, diagonal", axis));
    cam.vfov_deg = static_cast<float>(2.0 * std::atan(tan_half_v) * 180.0 / std::numbers::pi);

    // Mitsuba's camera looks along +Z of its to_world frame with +Y up and +X to the left; a mirroring
    // frame would flip the image, which twinray's camera cannot.
    if (glm::determinant(glm::dmat3(to_world)) < 0.0) fail(node, "a mirroring sensor to_world is not supported");
    const glm::dvec3 origin(to_world[3]);
    const glm::dvec3 forward = glm::normalize(glm::dvec3(to_world[2]));
    const glm::dvec3 up = glm::normalize(glm::dvec3(to_world[1]));
    cam.position = glm::vec3(origin);
    // One unit ahead; far from the origin a unit step can vanish in float, so step by the distance then.
    cam.look_at = glm::vec3(origin + forward * std::max(1.0, 1e-3 * glm::length(origin)));
    cam.up = glm::vec3(up);
    auto finite = [](const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); };
    if (!finite(cam.position) || !finite(cam.look_at) || !finite(cam.up) || cam.look_at == cam.position)
      fail(node, "the sensor's to_world places the camera outside float range");
  }

  void parse_sampler(const pugi::xml_node& node) {
    expect_attributes(node, {"type", "id", "name"});
    const std::string type = attr(node, "type");
    static const std::set<std::string> kSamplers = {"independent", "stratified", "multijitter", "orthogonal", "ldsampler"};
    if (!kSamplers.count(type))
      fail(node, fmt::format("sampler '{}' is not supported (independent, stratified, multijitter, orthogonal, ldsampler)", type));
    Properties p(*this, node);
    scene_.render.spp = p.integer("sample_count", 1, kMaxSpp).value_or(4);
    if (const auto seed = p.integer("seed", 0, std::numeric_limits<int>::max())) scene_.render.seed = static_cast<std::uint64_t>(*seed);
    (void)p.boolean("jitter");  // stratification detail of Mitsuba's samplers: no effect on the expected image
    (void)p.number("strength");
    p.finish();
  }

  void parse_film(const pugi::xml_node& node) {
    expect_attributes(node, {"type", "id", "name"});
    const std::string type = attr(node, "type");
    if (type != "hdrfilm") fail(node, fmt::format("film '{}' is not supported (hdrfilm)", type));
    Properties p(*this, node);
    scene_.camera.width = p.integer("width", 1, kMaxImageSide).value_or(768);
    scene_.camera.height = p.integer("height", 1, kMaxImageSide).value_or(576);
    (void)p.string("pixel_format");  // output formats: twinray writes RGB EXR and PNG whatever they say
    (void)p.string("component_format");
    (void)p.string("file_format");
    (void)p.boolean("banner");
    if (const auto border = p.boolean("sample_border"); border && *border)
      fail(node, "sample_border is not supported (it only matters for filters wider than a pixel)");
    p.finish({"rfilter"});
    bool box = false;
    for (const pugi::xml_node& child : node.children()) {
      if (child.type() != pugi::node_element || std::string_view(child.name()) != "rfilter") continue;
      expect_attributes(child, {"type", "id", "name"});
      const std::string f = attr(child, "type");
      if (f != "box") fail(child, fmt::format("rfilter '{}' is not supported: twinray's pixel is the mean of its samples (box)", f));
      Properties(*this, child).finish();
      box = true;
    }
    if (!box) fail(node, "the film has no <rfilter type=\"box\"/>: Mitsuba's default is a Gaussian filter, twinray's a box");
  }

  // ---- BSDFs -----------------------------------------------------------------------------------------

  BsdfDesc parse_bsdf(const pugi::xml_node& node) {
    expect_attributes(node, {"type", "id", "name"});
    const std::string type = attr(node, "type");
    BsdfDesc b;
    b.name = node.attribute("id") ? attr(node, "id") : fmt::format("bsdf at line {}", lines_.line_of(node.offset_debug()));
    Properties p(*this, node);
    if (type == "twosided") {
      p.finish({"bsdf"});
      std::vector<pugi::xml_node> inner;
      for (const pugi::xml_node& child : node.children("bsdf")) inner.push_back(child);
      if (inner.size() != 1)
        fail(node, "twosided with two BSDFs (a different one per side) is not supported: give one");
      BsdfDesc in = parse_bsdf(inner[0]);
      if (in.kind == BsdfDesc::Kind::Dielectric) fail(inner[0], "twosided around a dielectric is not supported");
      if (in.two_sided) fail(inner[0], "twosided inside twosided");
      in.two_sided = true;
      in.name = b.name;
      return b = in;
    }
    if (type == "diffuse") {
      b.kind = BsdfDesc::Kind::Diffuse;
      b.color = p.reflectance("reflectance").value_or(glm::vec3(0.5f));
    } else if (type == "conductor") {
      b.kind = BsdfDesc::Kind::Conductor;
      const std::string material = p.string("material").value_or("none");
      if (material != "none")
        fail(node, fmt::format("conductor material '{}' is not supported: twinray's mirror is material \"none\" (a perfect "
                               "reflector tinted by specular_reflectance)", material));
      b.color = p.reflectance("specular_reflectance").value_or(glm::vec3(1.0f));
    } else if (type == "dielectric") {
      b.kind = BsdfDesc::Kind::Dielectric;
      const double int_ior = ior(p, "int_ior", "bk7");
      const double ext_ior = ior(p, "ext_ior", "air");
      for (const char* name : {"specular_reflectance", "specular_transmittance"})
        if (const auto c = p.color(name); c && *c != glm::vec3(1.0f))
          fail(node, std::string(name) + " other than 1 is not supported by twinray's glass");
      b.ior = static_cast<float>(int_ior / ext_ior);
      b.two_sided = true;  // a dielectric has two sides by nature
    } else {
      fail(node, fmt::format("bsdf '{}' is not supported (diffuse, conductor, dielectric, twosided)", type));
    }
    p.finish();
    return b;
  }

  double ior(Properties& p, const char* name, const char* fallback) {
    if (const auto n = p.take(name, {"float", "string"})) {
      expect_attributes(*n, {"name", "value"});
      const std::string text = attr(*n, "value");
      if (std::string_view(n->name()) == "string") {
        const auto it = kNamedIor.find(text);
        if (it == kNamedIor.end()) fail(*n, fmt::format("unknown index of refraction '{}'", text));
        return it->second;
      }
      const double v = number(*n, text);
      if (!(v > 0.0)) fail(*n, fmt::format("{} must be positive", name));
      return v;
    }
    return kNamedIor.at(fallback);
  }

  void parse_top_level_bsdf(const pugi::xml_node& node) {
    if (!node.attribute("id")) fail(node, "a top-level <bsdf> needs an id (shapes refer to it with <ref id=\"...\"/>)");
    const std::string id = attr(node, "id");
    BsdfDesc b = parse_bsdf(node);
    if (!bsdfs_.emplace(id, b).second) fail(node, fmt::format("id '{}' is defined twice", id));
  }

  // ---- shapes -------------------------------------------------------------------------------------------

  std::uint32_t material_for(const BsdfDesc& b, const std::optional<glm::vec3>& radiance, const pugi::xml_node& shape) {
    Material m;
    m.two_sided = b.two_sided;
    if (radiance) {
      if (b.kind != BsdfDesc::Kind::Diffuse)
        fail(shape, "an area emitter on a conductor or dielectric shape is not supported: twinray's emissive surfaces reflect diffusely");
      m.type = MaterialType::Emissive;
      m.radiance = *radiance;
      m.albedo = b.color;
      m.name = fmt::format("{} + area emitter ({:.6g}, {:.6g}, {:.6g})", b.name, radiance->x, radiance->y, radiance->z);
    } else {
      m.name = b.name;
      switch (b.kind) {
        case BsdfDesc::Kind::Diffuse: m.type = MaterialType::Diffuse; m.albedo = b.color; break;
        case BsdfDesc::Kind::Conductor: m.type = MaterialType::Mirror; m.reflectance = b.color; break;
        case BsdfDesc::Kind::Dielectric: m.type = MaterialType::Glass; m.ior = b.ior; break;
      }
    }
    for (std::size_t i = 0; i < scene_.materials.size(); ++i) {
      const Material& o = scene_.materials[i];
      if (o.name == m.name && o.type == m.type && o.albedo == m.albedo && o.reflectance == m.reflectance &&
          o.ior == m.ior && o.radiance == m.radiance && o.two_sided == m.two_sided)
        return static_cast<std::uint32_t>(i);
    }
    scene_.materials.push_back(m);
    return static_cast<std::uint32_t>(scene_.materials.size() - 1);
  }

  void parse_shape(const pugi::xml_node& node) {
    expect_attributes(node, {"type", "id", "name"});
    const std::string type = attr(node, "type");
    const auto geom_id = static_cast<std::uint32_t>(scene_.shapes.size());
    ShapeInfo info;
    info.name = node.attribute("id") ? attr(node, "id") : fmt::format("{} at line {}", type, lines_.line_of(node.offset_debug()));
    Properties p(*this, node);
    const std::optional<glm::dmat4> to_world = p.transform("to_world");
    const bool flip = p.boolean("flip_normals").value_or(false);

    if (type == "obj" || type == "ply") {
      info.kind = ShapeKind::Mesh;
      const std::string filename = p.string("filename").value_or("");
      if (filename.empty()) fail(node, fmt::format("shape '{}' needs a filename", type));
      info.file = resolve_relative(base_dir_, filename);
      if (!p.boolean("face_normals").value_or(false))
        fail(node, "smooth vertex normals are not supported: twinray shades with geometric (face) normals; add "
                   "<boolean name=\"face_normals\" value=\"true\"/>");
      (void)p.boolean("flip_tex_coords");  // texture coordinates: twinray has no textures
      TriangleMesh mesh = read_mesh(info.file, type, node);
      finish_mesh(std::move(mesh), geom_id, to_world, flip, node);
    } else if (type == "rectangle" || type == "cube") {
      info.kind = ShapeKind::Mesh;
      finish_mesh(type == "rectangle" ? unit_rectangle() : unit_cube(), geom_id, to_world, flip, node);
    } else if (type == "sphere") {
      info.kind = ShapeKind::Sphere;
      if (flip) fail(node, "flip_normals on a sphere is not supported: twinray's spheres face outward");
      Sphere s;
      s.geom_id = geom_id;
      s.center = glm::vec3(p.point("center").value_or(glm::dvec3(0.0)));
      const double radius = p.number("radius").value_or(1.0);
      if (!(radius > 0.0)) fail(node, "the sphere's radius must be positive");
      s.radius = static_cast<float>(radius);
      if (to_world) {
        try {
          transform_sphere(s, affine(*to_world));
        } catch (const std::invalid_argument& e) {
          fail(node, e.what());
        }
      }
      if (!std::isfinite(s.center.x) || !std::isfinite(s.center.y) || !std::isfinite(s.center.z) ||
          !std::isfinite(s.radius) || !(s.radius > 0.0f))
        fail(node, "the sphere lies outside float range (or its radius rounds to 0)");
      scene_.geometry.spheres.push_back(s);
    } else {
      fail(node, fmt::format("shape '{}' is not supported (obj, ply, sphere, rectangle, cube)", type));
    }
    p.finish({"bsdf", "ref", "emitter"});

    std::optional<BsdfDesc> bsdf;
    std::optional<glm::vec3> radiance;
    for (const pugi::xml_node& child : node.children()) {
      if (child.type() != pugi::node_element) continue;
      const std::string_view tag = child.name();
      if (tag == "bsdf" || tag == "ref") {
        if (bsdf) fail(child, "a shape with two BSDFs");
        if (tag == "bsdf") {
          bsdf = parse_bsdf(child);
        } else {
          expect_attributes(child, {"id", "name"});
          const std::string id = attr(child, "id");
          const auto it = bsdfs_.find(id);
          if (it == bsdfs_.end()) {
            std::string known;
            for (const auto& [k, v] : bsdfs_) known += (known.empty() ? "" : ", ") + k;
            fail(child, fmt::format("no bsdf with id '{}' (defined before this line: {})", id, known.empty() ? "none" : known));
          }
          bsdf = it->second;
        }
      } else if (tag == "emitter") {
        expect_attributes(child, {"type", "id", "name"});
        if (radiance) fail(child, "a shape with two emitters");
        const std::string etype = attr(child, "type");
        if (etype != "area") fail(child, fmt::format("emitter '{}' inside a shape is not supported (area)", etype));
        Properties ep(*this, child);
        radiance = ep.color("radiance").value_or(glm::vec3(1.0f));
        ep.finish();
      }
    }
    if (!bsdf) {
      // Mitsuba's default BSDF: one-sided diffuse with reflectance 0.5.
      bsdf = BsdfDesc{};
      bsdf->name = "default diffuse";
    }
    info.material = material_for(*bsdf, radiance, node);
    scene_.shapes.push_back(std::move(info));
  }

  TriangleMesh read_mesh(const std::filesystem::path& path, const std::string& type, const pugi::xml_node& node) {
    try {
      require_regular_file(path);
      const std::string bytes = read_input_file(path);
      return type == "obj" ? parse_obj(bytes, path, scene_.report) : parse_ply(bytes, path, scene_.report);
    } catch (const InputError& e) {
      throw InputError(e.file(), e.where(),
                       fmt::format("{} (mesh referenced at line {} of {})", e.message(), lines_.line_of(node.offset_debug()),
                                   file_.string()));
    }
  }

  void finish_mesh(TriangleMesh mesh, std::uint32_t geom_id, const std::optional<glm::dmat4>& to_world, bool flip,
                   const pugi::xml_node& node) {
    mesh.geom_id = geom_id;
    bool reverse = flip;
    if (to_world) {
      const AffineTransform t = affine(*to_world);
      transform_mesh(mesh, t);
      // transform_mesh keeps the front on the same side of the surface under a mirroring transform by
      // reversing the winding; Mitsuba takes the face normal from the transformed vertices as they are, so
      // its front flips: undo the reversal.
      if (t.flips_orientation()) reverse = !reverse;
      for (const glm::vec3& v : mesh.positions)
        if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z))
          fail(node, "the transform moves vertices out of float range");
    }
    if (reverse)
      for (glm::uvec3& tri : mesh.indices) std::swap(tri.y, tri.z);
    scene_.geometry.meshes.push_back(std::move(mesh));
  }

  static TriangleMesh unit_rectangle() {
    TriangleMesh m;
    m.positions = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}};
    m.indices = {{0, 1, 2}, {0, 2, 3}};  // counter-clockwise seen from +Z: the front faces +Z, as in Mitsuba
    return m;
  }

  static TriangleMesh unit_cube() {
    TriangleMesh m;
    for (int axis = 0; axis < 3; ++axis)
      for (const float side : {-1.0f, 1.0f}) {
        // Face at coordinate `side` along `axis`, corners counter-clockwise seen from outside.
        const int u = (axis + 1) % 3, v = (axis + 2) % 3;
        const auto base = static_cast<std::uint32_t>(m.positions.size());
        const float corners[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
        for (const auto& c : corners) {
          glm::vec3 p(0.0f);
          p[axis] = side;
          p[u] = c[0];
          p[v] = c[1];
          m.positions.push_back(p);
        }
        if (side > 0) m.indices.insert(m.indices.end(), {{base, base + 1, base + 2}, {base, base + 2, base + 3}});
        else m.indices.insert(m.indices.end(), {{base, base + 2, base + 1}, {base, base + 3, base + 2}});
      }
    return m;
  }

  // ---- environment --------------------------------------------------------------------------------------

  void parse_environment(const pugi::xml_node& node) {
    expect_attributes(node, {"type", "id", "name"});
    const std::string type = attr(node, "type");
    if (scene_.environment.type != EnvironmentType::None)
      fail(node, "a second environment emitter: twinray has one environment");
    Environment& env = scene_.environment;
    Properties p(*this, node);
    if (type == "constant") {
      env.type = EnvironmentType::Constant;
      env.radiance = p.color("radiance").value_or(glm::vec3(1.0f));
    } else if (type == "envmap") {
      env.type = EnvironmentType::Image;
      env.filter = EnvironmentFilter::Bilinear;  // Mitsuba's envmap interpolates bilinearly, twinray does the same
      const std::string filename = p.string("filename").value_or("");
      if (filename.empty()) fail(node, "envmap needs a filename");
      env.image = resolve_relative(base_dir_, filename);
      try {
        require_regular_file(env.image);
      } catch (const InputError& e) {
        throw InputError(e.file(), e.where(), fmt::format("{} (environment map referenced at line {} of {})", e.message(),
                                                          lines_.line_of(node.offset_debug()), file_.string()));
      }
      const double scale = p.number("scale").value_or(1.0);
      if (scale < 0.0) fail(node, "scale must be non-negative");
      env.scale = static_cast<float>(scale);
      const glm::dmat3 r(p.transform("to_world").value_or(glm::dmat4(1.0)));
      // Only rotations about +Y: the axis must stay put and the matrix must be orthonormal.
      const double tol = 1e-5;
      const bool about_y = std::abs(r[1][1] - 1.0) < tol && std::abs(r[0][1]) < tol && std::abs(r[2][1]) < tol &&
                           std::abs(r[1][0]) < tol && std::abs(r[1][2]) < tol &&
                           std::abs(r[0][0] * r[0][0] + r[0][2] * r[0][2] - 1.0) < tol &&
                           std::abs(r[0][0] - r[2][2]) < tol && std::abs(r[2][0] + r[0][2]) < tol;
      if (!about_y) fail(node, "envmap to_world must be a rotation about +Y (twinray rotates maps about +Y only)");
      // Mitsuba's unrotated map faces its centre column towards +Z, twinray's towards -Z: twinray's rotation
      // is Mitsuba's minus 180 degrees (docs/mitsuba.md).
      const double theta = std::atan2(-r[0][2], r[0][0]) * 180.0 / std::numbers::pi;
      double rotation = theta - 180.0;
      rotation -= 360.0 * std::floor((rotation + 180.0) / 360.0);  // into [-180, 180)
      env.rotation_deg = static_cast<float>(rotation);
    } else {
      fail(node, fmt::format("emitter '{}' is not supported at the top level (constant, envmap; area emitters go inside shapes)", type));
    }
    p.finish();
  }

  // ---- clipping -----------------------------------------------------------------------------------------

  void check_clip_planes() const {
    const Bounds3 b = scene_.geometry.bounds();
    if (b.empty()) return;
    const glm::dvec3 eye(scene_.camera.position);
    double farthest = 0.0;
    for (int i = 0; i < 8; ++i) {
      const glm::dvec3 corner((i & 1) ? b.hi.x : b.lo.x, (i & 2) ? b.hi.y : b.lo.y, (i & 4) ? b.hi.z : b.lo.z);
      farthest = std::max(farthest, glm::length(corner - eye));
    }
    // Spheres as large as a ground plane (radius 1000) reach far beyond what a camera sees of them: only
    // triangle meshes and small spheres are held to the far plane.
    if (farthest > far_clip_ && !scene_.geometry.has_spheres())
      fail(clip_node_, fmt::format("far_clip {} would clip the scene (its farthest point is {:.6g} from the camera), "
                                   "and twinray has no clip planes", far_clip_, farthest));
  }

  std::string_view text_;
  LineIndex lines_;
  const std::filesystem::path& file_;
  std::filesystem::path base_dir_;
  Scene& scene_;
  std::map<std::string, std::string> defaults_;
  std::map<std::string, BsdfDesc> bsdfs_;
  bool sensor_seen_ = false, integrator_seen_ = false;
  double near_clip_ = 1e-2, far_clip_ = 1e4;
  pugi::xml_node clip_node_;
};

}  // namespace

Scene parse_mitsuba_scene(std::string_view text, const std::filesystem::path& xml_file) {
  Scene scene;
  scene.source = xml_file;
  scene.render.spp = 4;  // Mitsuba's default sample count, until a sampler says otherwise
  MitsubaParser(text, xml_file, scene).parse();
  return scene;
}

Scene load_mitsuba_scene(const std::filesystem::path& xml_file) {
  const std::string text = read_input_file(xml_file);
  return parse_mitsuba_scene(text, xml_file);
}

}  // namespace twinray
