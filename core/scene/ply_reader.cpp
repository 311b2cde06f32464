#include "core/scene/ply_reader.h"

#include "core/scene/input_file.h"
#include "core/scene/text_parsing.h"
#include "core/util/input_error.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace twinray {
namespace {

enum class Format { Ascii, BinaryLittleEndian, BinaryBigEndian };

enum class ScalarType : std::uint8_t { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

std::optional<ScalarType> scalar_type_named(std::string_view name) {
  if (name == "char" || name == "int8") return ScalarType::Int8;
  if (name == "uchar" || name == "uint8") return ScalarType::UInt8;
  if (name == "short" || name == "int16") return ScalarType::Int16;
  if (name == "ushort" || name == "uint16") return ScalarType::UInt16;
  if (name == "int" || name == "int32") return ScalarType::Int32;
  if (name == "uint" || name == "uint32") return ScalarType::UInt32;
  if (name == "float" || name == "float32") return ScalarType::Float32;
  if (name == "double" || name == "float64") return ScalarType::Float64;
  return std::nullopt;
}

std::size_t size_of(ScalarType type) {
  switch (type) {
    case ScalarType::Int8: case ScalarType::UInt8: return 1;
    case ScalarType::Int16: case ScalarType::UInt16: return 2;
    case ScalarType::Int32: case ScalarType::UInt32: case ScalarType::Float32: return 4;
    case ScalarType::Float64: return 8;
  }
  return 0;
}

bool is_integer(ScalarType type) { return type != ScalarType::Float32 && type != ScalarType::Float64; }

// What the reader does with a property.
enum class Role : std::uint8_t { Skip, X, Y, Z, FaceIndices };

struct Property {
  std::string name;
  ScalarType type = ScalarType::Float32;  // the item type of a list
  bool is_list = false;
  ScalarType count_type = ScalarType::UInt8;
  Role role = Role::Skip;
};

struct Element {
  std::string name;
  std::uint64_t count = 0;
  std::vector<Property> properties;
  std::size_t header_line = 0;

  // Bytes one instance takes at least in a binary file (a list may be empty).
  std::size_t min_binary_size() const {
    std::size_t n = 0;
    for (const Property& p : properties) n += p.is_list ? size_of(p.count_type) : size_of(p.type);
    return n;
  }
  bool fixed_size() const {
    return std::none_of(properties.begin(), properties.end(), [](const Property& p) { return p.is_list; });
  }
};

template <class T>
T load(const unsigned char* p, bool swap) {
  unsigned char b[sizeof(T)];
  std::memcpy(b, p, sizeof(T));
  if (swap) std::reverse(b, b + sizeof(T));
  T v;
  std::memcpy(&v, b, sizeof(T));
  return v;
}

double decode_real(ScalarType type, const unsigned char* p, bool swap) {
  switch (type) {
    case ScalarType::Int8: return load<std::int8_t>(p, swap);
    case ScalarType::UInt8: return load<std::uint8_t>(p, swap);
    case ScalarType::Int16: return load<std::int16_t>(p, swap);
    case ScalarType::UInt16: return load<std::uint16_t>(p, swap);
    case ScalarType::Int32: return load<std::int32_t>(p, swap);
    case ScalarType::UInt32: return load<std::uint32_t>(p, swap);
    case ScalarType::Float32: return static_cast<double>(load<float>(p, swap));
    case ScalarType::Float64: return load<double>(p, swap);
  }
  return 0.0;
}

std::int64_t decode_integer(ScalarType type, const unsigned char* p, bool swap) {
  switch (type) {
    case ScalarType::Int8: return load<std::int8_t>(p, swap);
    case ScalarType::UInt8: return load<std::uint8_t>(p, swap);
    case ScalarType::Int16: return load<std::int16_t>(p, swap);
    case ScalarType::UInt16: return load<std::uint16_t>(p, swap);
    case ScalarType::Int32: return load<std::int32_t>(p, swap);
    case ScalarType::UInt32: return load<std::uint32_t>(p, swap);
    case ScalarType::Float32: case ScalarType::Float64: break;  // rejected in the header
  }
  return 0;
}

std::string format_real(double v) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buf[32];
  const std::to_chars_result r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

class PlyParser {
 public:
  PlyParser(std::string_view bytes, const std::filesystem::path& path, LoadReport& report)
      : bytes_(bytes), lines_(bytes), path_(path), report_(report) {}

  TriangleMesh parse() {
    parse_header();
    check_declared_sizes();
    // After the size check, so that a corrupt count is reported as such rather than as unsupported.
    if (vertex_element_ && vertex_element_->count > std::numeric_limits<std::uint32_t>::max())
      fail_line(vertex_element_->header_line, "more than 2^32-1 vertices are not supported");
    if (vertex_element_) mesh_.positions.reserve(static_cast<std::size_t>(vertex_element_->count) + 1);
    if (format_ == Format::Ascii) {
      for (const Element& e : elements_) read_ascii_element(e);
    } else {
      const std::string_view data = lines_.rest();
      data_ = reinterpret_cast<const unsigned char*>(data.data());
      data_size_ = data.size();
      data_offset_ = bytes_.size() - data.size();
      swap_ = (format_ == Format::BinaryLittleEndian) != (std::endian::native == std::endian::little);
      for (const Element& e : elements_) read_binary_element(e);
    }
    return std::move(mesh_);
  }

 private:
  [[noreturn]] void fail(const std::string& where, const std::string& message) const {
    throw InputError(path_, where, message);
  }
  [[noreturn]] void fail_line(std::size_t line, const std::string& message) const {
    fail("line " + std::to_string(line), message);
  }

  // ---- header -------------------------------------------------------------------------------------------

  void parse_header() {
    std::string_view line;
    if (!lines_.next(line) || line != "ply") fail_line(1, "not a PLY file (the first line must be 'ply')");
    bool have_format = false;
    for (;;) {
      if (!lines_.next(line)) fail_line(lines_.line_number(), "PLY header has no 'end_header' line");
      const std::size_t n = lines_.line_number();
      std::string_view rest = line;
      const std::string_view keyword = text::next_token(rest);
      if (keyword == "end_header") break;
      if (keyword.empty() || keyword == "comment" || keyword == "obj_info") continue;
      if (keyword == "format") {
        const std::string_view name = text::next_token(rest);
        const std::string_view version = text::next_token(rest);
        if (name == "ascii") format_ = Format::Ascii;
        else if (name == "binary_little_endian") format_ = Format::BinaryLittleEndian;
        else if (name == "binary_big_endian") format_ = Format::BinaryBigEndian;
        else fail_line(n, "unknown PLY format '" + std::string(name) +
                              "' (expected ascii, binary_little_endian or binary_big_endian)");
        if (version != "1.0") fail_line(n, "unsupported PLY version '" + std::string(version) + "' (expected 1.0)");
        have_format = true;
      } else if (keyword == "element") {
        parse_element_line(rest, n);
      } else if (keyword == "property") {
        parse_property_line(rest, n);
      } else {
        fail_line(n, "unknown PLY header keyword '" + std::string(keyword) + "'");
      }
    }
    const std::size_t end_line = lines_.line_number();
    if (!have_format) fail_line(end_line, "PLY header has no 'format' line");
    for (const Element& e : elements_) {
      if (e.name == "vertex") vertex_element_ = &e;
      if (e.name == "face") face_element_ = &e;
    }
    if (vertex_element_) {
      for (Role axis : {Role::X, Role::Y, Role::Z}) {
        const bool found = std::any_of(vertex_element_->properties.begin(), vertex_element_->properties.end(),
                                       [axis](const Property& p) { return p.role == axis; });
        if (!found)
          fail_line(vertex_element_->header_line, "vertex element has no scalar property '" +
                                                      std::string(axis == Role::X ? "x" : axis == Role::Y ? "y" : "z") +
                                                      "'");
      }
    }
    if (face_element_) {
      const bool found = std::any_of(face_element_->properties.begin(), face_element_->properties.end(),
                                     [](const Property& p) { return p.role == Role::FaceIndices; });
      if (!found)
        fail_line(face_element_->header_line, "face element has no list property 'vertex_indices' or 'vertex_index'");
      if (face_element_->count > 0 && !vertex_element_)
        fail_line(face_element_->header_line, "faces but no vertex element");
    }
  }

  void parse_element_line(std::string_view rest, std::size_t line) {
    Element e;
    e.name = std::string(text::next_token(rest));
    const std::string_view count = text::next_token(rest);
    if (e.name.empty() || count.empty()) fail_line(line, "expected 'element <name> <count>'");
    if (text::parse_number(count, e.count) != text::NumberStatus::Ok)
      fail_line(line, "invalid element count '" + std::string(count) + "'");
    for (const Element& other : elements_)
      if (other.name == e.name) fail_line(line, "element '" + e.name + "' is declared twice");
    e.header_line = line;
    elements_.push_back(std::move(e));
  }

  ScalarType parse_type(std::string_view name, std::size_t line) const {
    const std::optional<ScalarType> type = scalar_type_named(name);
    if (!type) fail_line(line, "unknown PLY property type '" + std::string(name) + "'");
    return *type;
  }

  void parse_property_line(std::string_view rest, std::size_t line) {
    if (elements_.empty()) fail_line(line, "'property' before any 'element'");
    Element& element = elements_.back();
    Property p;
    std::string_view type_name = text::next_token(rest);
    if (type_name == "list") {
      p.is_list = true;
      p.count_type = parse_type(text::next_token(rest), line);
      type_name = text::next_token(rest);
      if (!is_integer(p.count_type)) fail_line(line, "list count type must be an integer type");
    }
    p.type = parse_type(type_name, line);
    p.name = std::string(text::next_token(rest));
    if (p.name.empty()) fail_line(line, "property has no name");
    for (const Property& other : element.properties)
      if (other.name == p.name) fail_line(line, "property '" + p.name + "' is declared twice");
    if (element.name == "vertex" && !p.is_list) {
      if (p.name == "x") p.role = Role::X;
      if (p.name == "y") p.role = Role::Y;
      if (p.name == "z") p.role = Role::Z;
    }
    if (element.name == "face" && p.is_list && (p.name == "vertex_indices" || p.name == "vertex_index")) {
      if (!is_integer(p.type)) fail_line(line, "face vertex indices must have an integer type");
      const bool already = std::any_of(element.properties.begin(), element.properties.end(),
                                       [](const Property& q) { return q.role == Role::FaceIndices; });
      if (already) fail_line(line, "face element has both 'vertex_indices' and 'vertex_index'");
      p.role = Role::FaceIndices;
    }
    element.properties.push_back(std::move(p));
  }

  // Rejects element counts the file cannot possibly hold before any allocation is sized by them: a corrupt
  // header declaring 10^12 vertices must fail at once, not exhaust memory or loop for hours.
  void check_declared_sizes() const {
    const std::size_t available = lines_.rest().size();
    // The last ASCII value may end the file without a separator.
    const std::uint64_t budget = available + (format_ == Format::Ascii ? 1 : 0);
    std::uint64_t needed = 0;
    for (const Element& e : elements_) {
      // ASCII: every value takes at least one character plus a separator (the last one may end the file).
      const std::uint64_t per_instance = format_ == Format::Ascii ? 2 * e.properties.size() : e.min_binary_size();
      if (per_instance == 0 || e.count == 0) continue;
      // Invariant: needed <= budget, so the subtraction cannot wrap.
      if (e.count > (budget - needed) / per_instance)
        fail_line(e.header_line, "header declares " + std::to_string(e.count) + " '" + e.name +
                                     "' elements, but the " + std::to_string(available) +
                                     " bytes after the header cannot hold them (file truncated or header corrupt)");
      needed += e.count * per_instance;
    }
  }

  // ---- shared -------------------------------------------------------------------------------------------

  // Location strings are only built on the error path: the loops below run per vertex and corner.
  // Returns an error message, or empty when `value` fits a finite float.
  static std::string coordinate_problem(double value) {
    if (!std::isfinite(value)) return "non-finite vertex coordinate (" + format_real(value) + ")";
    if (!std::isfinite(static_cast<float>(value)))
      return "vertex coordinate " + format_real(value) + " is out of float range";
    return {};
  }

  static int axis_of(Role role) { return static_cast<int>(role) - static_cast<int>(Role::X); }

  bool index_in_range(std::int64_t index) const {
    return index >= 0 && static_cast<std::uint64_t>(index) < vertex_element_->count;
  }
  std::string index_problem(std::int64_t index) const {
    return "vertex index " + std::to_string(index) + " out of range (file has " +
           std::to_string(vertex_element_->count) + " vertices)";
  }

  void emit_polygon() {
    if (corners_.size() < 3) {
      ++report_.degenerate_triangles;  // nothing to hit, like a zero-area triangle
      return;
    }
    if (corners_.size() > 3) ++report_.polygons_triangulated;
    for (std::size_t k = 1; k + 1 < corners_.size(); ++k)
      mesh_.indices.emplace_back(corners_[0], corners_[k], corners_[k + 1]);
  }

  // ---- binary -------------------------------------------------------------------------------------------

  std::string binary_where(const Element& e, std::uint64_t i) const {
    if (&e == vertex_element_) return "vertex " + std::to_string(i);
    if (&e == face_element_) return "face " + std::to_string(i);
    return "byte " + std::to_string(data_offset_ + pos_);
  }

  const unsigned char* take(std::size_t n, const Element& e, std::uint64_t i) {
    if (n > data_size_ - pos_)
      fail(binary_where(e, i), "file is truncated: element '" + e.name + "' " + std::to_string(i) + " of " +
                                   std::to_string(e.count) + " needs more bytes than remain");
    const unsigned char* p = data_ + pos_;
    pos_ += n;
    return p;
  }

  void read_binary_element(const Element& e) {
    if (&e != vertex_element_ && &e != face_element_ && e.fixed_size()) {
      // Nothing to read: skip the whole block (its size was checked against the file in the header).
      const std::uint64_t n = e.count * e.min_binary_size();
      take(static_cast<std::size_t>(n), e, e.count > 0 ? e.count - 1 : 0);
      return;
    }
    for (std::uint64_t i = 0; i < e.count; ++i) {
      glm::vec3 p(0.0f);
      corners_.clear();
      for (const Property& prop : e.properties) {
        if (!prop.is_list) {
          const unsigned char* v = take(size_of(prop.type), e, i);
          if (prop.role == Role::Skip) continue;
          const double value = decode_real(prop.type, v, swap_);
          if (const std::string problem = coordinate_problem(value); !problem.empty()) fail(binary_where(e, i), problem);
          p[axis_of(prop.role)] = static_cast<float>(value);
          continue;
        }
        const std::int64_t count = decode_integer(prop.count_type, take(size_of(prop.count_type), e, i), swap_);
        if (count < 0) fail(binary_where(e, i), "negative list length " + std::to_string(count));
        const std::size_t item = size_of(prop.type);
        if (static_cast<std::uint64_t>(count) > (data_size_ - pos_) / item)
          fail(binary_where(e, i), "file is truncated: list '" + prop.name + "' declares " + std::to_string(count) +
                                       " items but only " + std::to_string(data_size_ - pos_) + " bytes remain");
        const unsigned char* items = take(static_cast<std::size_t>(count) * item, e, i);
        if (prop.role != Role::FaceIndices) continue;
        for (std::int64_t k = 0; k < count; ++k) {
          const std::int64_t index = decode_integer(prop.type, items + static_cast<std::size_t>(k) * item, swap_);
          if (!index_in_range(index)) fail(binary_where(e, i), index_problem(index));
          corners_.push_back(static_cast<std::uint32_t>(index));
        }
      }
      if (&e == vertex_element_) mesh_.positions.push_back(p);
      if (&e == face_element_) emit_polygon();
    }
  }

  // ---- ascii --------------------------------------------------------------------------------------------

  void read_ascii_element(const Element& e) {
    if (e.properties.empty()) return;
    for (std::uint64_t i = 0; i < e.count; ++i) {
      std::string_view line;
      do {
        if (!lines_.next(line))
          fail_line(lines_.line_number(), "file ends after " + std::to_string(i) + " of " + std::to_string(e.count) +
                                              " '" + e.name + "' elements");
      } while (text::only_blanks(line));
      const std::size_t n = lines_.line_number();
      glm::vec3 p(0.0f);
      corners_.clear();
      std::string_view rest = line;
      for (const Property& prop : e.properties) {
        if (!prop.is_list) {
          const std::string_view token = next_value(rest, e, prop, n);
          if (prop.role == Role::Skip) continue;
          // Straight to float: text -> double -> float could round twice.
          float value = 0.0f;
          const text::NumberStatus status = text::parse_real(token, value);
          if (status == text::NumberStatus::Invalid) fail_line(n, "invalid number '" + std::string(token) + "'");
          if (status == text::NumberStatus::OutOfRange)
            fail_line(n, "vertex coordinate " + std::string(token) + " is out of float range");
          if (!std::isfinite(value)) fail_line(n, coordinate_problem(static_cast<double>(value)));
          p[axis_of(prop.role)] = value;
          continue;
        }
        const std::int64_t count = parse_ascii_integer(next_value(rest, e, prop, n), n);
        if (count < 0) fail_line(n, "negative list length " + std::to_string(count));
        for (std::int64_t k = 0; k < count; ++k) {
          const std::string_view token = next_value(rest, e, prop, n);
          if (prop.role != Role::FaceIndices) continue;
          const std::int64_t index = parse_ascii_integer(token, n);
          if (!index_in_range(index)) fail_line(n, index_problem(index));
          corners_.push_back(static_cast<std::uint32_t>(index));
        }
      }
      if (!text::only_blanks(rest)) fail_line(n, "more values than the header declares for element '" + e.name + "'");
      if (&e == vertex_element_) mesh_.positions.push_back(p);
      if (&e == face_element_) emit_polygon();
    }
  }

  std::string_view next_value(std::string_view& rest, const Element& e, const Property& prop, std::size_t line) const {
    const std::string_view token = text::next_token(rest);
    if (token.empty())
      fail_line(line, "too few values for element '" + e.name + "' (missing property '" + prop.name + "')");
    return token;
  }

  std::int64_t parse_ascii_integer(std::string_view token, std::size_t line) const {
    std::int64_t v = 0;
    if (text::parse_number(token, v) != text::NumberStatus::Ok)
      fail_line(line, "invalid integer '" + std::string(token) + "'");
    return v;
  }

  std::string_view bytes_;
  text::LineReader lines_;
  const std::filesystem::path& path_;
  LoadReport& report_;

  Format format_ = Format::Ascii;
  std::vector<Element> elements_;
  const Element* vertex_element_ = nullptr;
  const Element* face_element_ = nullptr;

  const unsigned char* data_ = nullptr;
  std::size_t data_size_ = 0;
  std::size_t data_offset_ = 0;  // of data_ within the file, for "byte N" locations
  std::size_t pos_ = 0;
  bool swap_ = false;

  TriangleMesh mesh_;
  std::vector<std::uint32_t> corners_;  // reused across faces
};

}  // namespace

TriangleMesh parse_ply(std::string_view bytes, const std::filesystem::path& path, LoadReport& report) {
  return PlyParser(bytes, path, report).parse();
}

TriangleMesh read_ply(const std::filesystem::path& path, LoadReport& report) {
  const std::string bytes = read_input_file(path);
  return parse_ply(bytes, path, report);
}

}  // namespace twinray
