#pragma once
// Validating access to a parsed JSON document: every accessor checks type and range and reports failures
// as InputError at the value's JSON pointer, so the scene schema code reads as a list of fields.

#include <glm/vec3.hpp>
#include <nlohmann/json.hpp>

#include <cstdint>
#include <filesystem>
#include <initializer_list>
#include <optional>
#include <string>
#include <string_view>

namespace twinray {

// Ordered so that materials keep the order they are written in.
using Json = nlohmann::ordered_json;

// Parses `text`; a syntax error (or a number too large for a double) throws InputError at "line L:C", and
// a key repeated within one object throws InputError at the repeated key's JSON pointer.
Json parse_json_text(std::string_view text, const std::filesystem::path& file);

class JsonNode {
 public:
  JsonNode(const Json& value, std::string pointer, const std::filesystem::path& file)
      : value_(&value), pointer_(std::move(pointer)), file_(&file) {}

  const Json& json() const { return *value_; }
  const std::string& pointer() const { return pointer_; }
  const std::filesystem::path& file() const { return *file_; }
  [[noreturn]] void fail(const std::string& message) const;

  // ---- objects
  bool is_object() const { return value_->is_object(); }
  // Requires an object whose keys are all in `allowed` ("comment" is always allowed); an unknown key is
  // reported at its own pointer, with the closest allowed key as a suggestion.
  void expect_object(std::initializer_list<std::string_view> allowed) const;
  bool has(std::string_view key) const;
  JsonNode member(std::string_view key) const;  // required
  std::optional<JsonNode> optional_member(std::string_view key) const;

  // ---- arrays
  std::size_t expect_array() const;  // returns the size
  std::size_t expect_array_of_size(std::size_t n) const;
  JsonNode element(std::size_t index) const;

  // ---- scalars
  std::string as_string() const;
  bool as_bool() const;
  double as_double() const;  // any finite number
  float as_float() const;    // a finite number that is also finite as a float
  std::int64_t as_integer(std::int64_t lo, std::int64_t hi) const;  // an integer in [lo, hi]
  std::uint64_t as_unsigned() const;                                // an integer in [0, 2^64 - 1]
  glm::vec3 as_vec3() const;    // [x, y, z], finite floats
  glm::dvec3 as_dvec3() const;  // [x, y, z], finite doubles
  glm::vec3 as_color() const;   // [r, g, b] or a single number for grey; finite and non-negative

 private:
  const Json* value_;
  std::string pointer_;
  const std::filesystem::path* file_;
};

}  // namespace twinray
