#include "core/scene/obj_reader.h"

#include "core/scene/input_file.h"
#include "core/scene/text_parsing.h"
#include "core/util/input_error.h"

#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

// Why a hand-written parser rather than tinyobjloader (which the build also links):
// tinyobjloader 2.0rc10 turns a coordinate it cannot parse ("nan", "1.5e", "abc") silently into 0, does not
// range-check positive face indices, parses indices with atoi (undefined on overflow) and reports no line
// numbers for bad indices. Validating all that afterwards would mean re-tokenising every `v` and `f` line
// anyway, i.e. writing this parser a second time next to the first. For the subset a path tracer reads
// (positions and faces) a single pass with std::from_chars is shorter, reports "file:line: what", and is
// faster than tinyobjloader (which also builds normals/texcoords/shape arrays we would throw away).

namespace twinray {
namespace {

class ObjParser {
 public:
  ObjParser(std::string_view text, const std::filesystem::path& path, LoadReport& report)
      : lines_(text), path_(path), report_(report) {}

  TriangleMesh parse() {
    std::string_view line;
    while (lines_.next(line)) {
      statement_line_ = lines_.line_number();
      std::string_view rest = join_continued_lines(line);
      const std::string_view keyword = text::next_token(rest);
      if (keyword == "v") {
        parse_vertex(rest);
      } else if (keyword == "f") {
        parse_face(rest);
      }
      // Anything else (comments, vt, vn, vp, o, g, s, usemtl, mtllib, l, p, ...) carries nothing we render.
    }
    check_forward_references();
    return std::move(mesh_);
  }

 private:
  [[noreturn]] void fail(const std::string& message) const { fail_at(statement_line_, message); }
  [[noreturn]] void fail_at(std::size_t line, const std::string& message) const {
    throw InputError(path_, "line " + std::to_string(line), message);
  }

  // A statement whose last non-blank character is a backslash continues on the next line (OBJ spec,
  // "\ line continuation": exporters wrap long faces this way). Comment lines never continue: Windows
  // paths in comments end in a backslash. Errors name the statement's first line.
  std::string_view join_continued_lines(std::string_view line) {
    std::string_view first_token = line;
    if (!ends_in_backslash(line) || text::next_token(first_token).starts_with('#')) return line;
    joined_.clear();
    do {
      line.remove_suffix(line.size() - line.find_last_of('\\'));
      joined_.append(line).push_back(' ');
    } while (ends_in_backslash(line = next_physical_line()));
    joined_.append(line);
    return joined_;
  }
  static bool ends_in_backslash(std::string_view line) {
    std::size_t end = line.size();
    while (end > 0 && text::is_blank(line[end - 1])) --end;
    return end > 0 && line[end - 1] == '\\';
  }
  // A backslash on the file's last line continues into nothing.
  std::string_view next_physical_line() {
    std::string_view line;
    return lines_.next(line) ? line : std::string_view();
  }

  void parse_vertex(std::string_view rest) {
    glm::vec3 p;
    for (int axis = 0; axis < 3; ++axis) {
      const std::string_view token = text::next_token(rest);
      if (token.empty()) fail("vertex needs three coordinates, found " + std::to_string(axis));
      switch (text::parse_real(token, p[axis])) {
        case text::NumberStatus::Ok: break;
        case text::NumberStatus::OutOfRange: fail("coordinate '" + std::string(token) + "' is out of float range");
        case text::NumberStatus::Invalid: fail("invalid coordinate '" + std::string(token) + "'");
      }
      if (!std::isfinite(p[axis])) fail("non-finite coordinate '" + std::string(token) + "'");
    }
    // Further numbers (w, or the r g b of the vertex-colour extension) are not used.
    if (mesh_.positions.size() == std::numeric_limits<std::uint32_t>::max())
      fail("more than 2^32-1 vertices are not supported");
    mesh_.positions.push_back(p);
  }

  // A face corner is "v", "v/vt", "v//vn" or "v/vt/vn"; only v matters here. Indices are 1-based, negative
  // ones count back from the last vertex defined so far.
  std::uint32_t parse_corner(std::string_view token) {
    const std::size_t slash = token.find('/');
    const std::string_view index_text = token.substr(0, slash);
    std::int64_t index = 0;
    const text::NumberStatus status = text::parse_number(index_text, index);
    if (status == text::NumberStatus::Invalid) fail("invalid face vertex '" + std::string(token) + "'");
    const std::int64_t defined = static_cast<std::int64_t>(mesh_.positions.size());
    if (index == 0) fail("face index 0 is invalid (OBJ indices start at 1)");
    if (status == text::NumberStatus::OutOfRange || index > std::numeric_limits<std::uint32_t>::max())
      fail("face index " + std::string(index_text) + " out of range");
    if (index < 0) {
      if (-index > defined)
        fail("relative face index " + std::to_string(index) + " out of range (" + std::to_string(defined) +
             " vertices defined before this line)");
      return static_cast<std::uint32_t>(defined + index);
    }
    // The OBJ spec wants vertices defined before use, but readers commonly accept forward references:
    // check those against the final vertex count at the end of the file.
    if (index > defined && (forward_.empty() || index > forward_.back().index))
      forward_.push_back({index, statement_line_});
    return static_cast<std::uint32_t>(index - 1);
  }

  void parse_face(std::string_view rest) {
    corners_.clear();
    for (std::string_view token = text::next_token(rest); !token.empty(); token = text::next_token(rest))
      corners_.push_back(parse_corner(token));
    if (corners_.size() < 3) {
      // Syntactically a face; geometrically nothing to hit. Counted like any other zero-area triangle.
      ++report_.degenerate_triangles;
      return;
    }
    if (corners_.size() > 3) ++report_.polygons_triangulated;
    for (std::size_t k = 1; k + 1 < corners_.size(); ++k)
      mesh_.indices.emplace_back(corners_[0], corners_[k], corners_[k + 1]);
  }

  void check_forward_references() const {
    // forward_ records each forward reference larger than all before it. The first out-of-range reference
    // in the file is therefore recorded (nothing earlier is larger), and every entry before it is in range:
    // the first recorded entry past the end is the first offending line.
    const std::int64_t total = static_cast<std::int64_t>(mesh_.positions.size());
    for (const ForwardReference& ref : forward_)
      if (ref.index > total)
        fail_at(ref.line, "face index " + std::to_string(ref.index) + " out of range (file has " +
                              std::to_string(total) + " vertices)");
  }

  struct ForwardReference {
    std::int64_t index;
    std::size_t line;
  };

  text::LineReader lines_;
  const std::filesystem::path& path_;
  LoadReport& report_;
  TriangleMesh mesh_;
  std::size_t statement_line_ = 0;       // first line of the statement being parsed
  std::string joined_;                   // a statement continued over several lines, joined
  std::vector<std::uint32_t> corners_;   // reused across faces
  std::vector<ForwardReference> forward_;  // strictly increasing indices beyond the vertices read so far
};

}  // namespace

TriangleMesh parse_obj(std::string_view text, const std::filesystem::path& path, LoadReport& report) {
  return ObjParser(text, path, report).parse();
}

TriangleMesh read_obj(const std::filesystem::path& path, LoadReport& report) {
  const std::string bytes = read_input_file(path);
  return parse_obj(bytes, path, report);
}

}  // namespace twinray
