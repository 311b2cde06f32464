#include "core/scene/json_reader.h"

#include "core/util/input_error.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_set>
#include <vector>

namespace twinray {
namespace {

// RFC 6901: '~' and '/' inside a key are escaped.
std::string escape_pointer_token(std::string_view key) {
  std::string out;
  for (char c : key) {
    if (c == '~') out += "~0";
    else if (c == '/') out += "~1";
    else out += c;
  }
  return out;
}

// Optimal string alignment distance: insertions, deletions, substitutions and swaps of neighbours each
// cost 1, so the common typos "fvo" (for "fov") and "radus" (for "radius") are both at distance 1.
std::size_t edit_distance(std::string_view a, std::string_view b) {
  std::vector<std::vector<std::size_t>> d(a.size() + 1, std::vector<std::size_t>(b.size() + 1));
  for (std::size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i)
    for (std::size_t j = 1; j <= b.size(); ++j) {
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1)});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  return d[a.size()][b.size()];
}

std::string describe_type(const Json& v) {
  switch (v.type()) {
    case Json::value_t::null: return "null";
    case Json::value_t::object: return "an object";
    case Json::value_t::array: return "an array";
    case Json::value_t::string: return "a string";
    case Json::value_t::boolean: return "a boolean";
    case Json::value_t::number_integer:
    case Json::value_t::number_unsigned: return "an integer";
    case Json::value_t::number_float: return "a number";
    default: return "a value of unsupported type";
  }
}

// Finds where nlohmann's DOM parser failed when its exception does not carry a position (number overflow,
// "1e999"): a second, throw-free SAX pass over the text stops at the same place and reports the offset.
struct ErrorLocator : nlohmann::json_sax<Json> {
  std::size_t byte = 0;
  std::string token;
  bool null() override { return true; }
  bool boolean(bool) override { return true; }
  bool number_integer(number_integer_t) override { return true; }
  bool number_unsigned(number_unsigned_t) override { return true; }
  bool number_float(number_float_t, const string_t&) override { return true; }
  bool string(string_t&) override { return true; }
  bool binary(binary_t&) override { return true; }
  bool start_object(std::size_t) override { return true; }
  bool key(string_t&) override { return true; }
  bool end_object() override { return true; }
  bool start_array(std::size_t) override { return true; }
  bool end_array() override { return true; }
  bool parse_error(std::size_t position, const std::string& last_token, const nlohmann::json::exception&) override {
    byte = position;
    token = last_token;
    return false;
  }
};

// JSON allows an object to repeat a key and nlohmann keeps the last value, so a scene with two "radius"
// keys would silently render the second. A SAX pass over the text (after the DOM parse succeeded) finds
// the first repeated key and its JSON pointer; the pass is linear, and hashing keeps objects with very
// many keys (fuzzed input) linear too.
struct DuplicateKeyFinder : nlohmann::json_sax<Json> {
  struct Container {
    bool is_array = false;
    std::size_t next_index = 0;
    std::unordered_set<std::string> keys;
    std::string child_token;  // pointer token of the member or element being read
  };
  std::vector<Container> open;
  bool found = false;
  std::string duplicate_pointer;
  std::string duplicate_key;

  void value_starts() {
    if (!open.empty() && open.back().is_array) open.back().child_token = std::to_string(open.back().next_index++);
  }
  bool null() override { return value_starts(), true; }
  bool boolean(bool) override { return value_starts(), true; }
  bool number_integer(number_integer_t) override { return value_starts(), true; }
  bool number_unsigned(number_unsigned_t) override { return value_starts(), true; }
  bool number_float(number_float_t, const string_t&) override { return value_starts(), true; }
  bool string(string_t&) override { return value_starts(), true; }
  bool binary(binary_t&) override { return value_starts(), true; }
  bool start_object(std::size_t) override {
    value_starts();
    open.emplace_back();
    return true;
  }
  bool key(string_t& k) override {
    Container& object = open.back();
    object.child_token = escape_pointer_token(k);
    if (object.keys.insert(k).second) return true;
    for (const Container& c : open) duplicate_pointer += "/" + c.child_token;
    duplicate_key = k;
    found = true;
    return false;  // stop at the first duplicate
  }
  bool end_object() override { return open.pop_back(), true; }
  bool start_array(std::size_t) override {
    value_starts();
    open.emplace_back().is_array = true;
    return true;
  }
  bool end_array() override { return open.pop_back(), true; }
  bool parse_error(std::size_t, const std::string&, const nlohmann::json::exception&) override { return false; }
};

// nlohmann positions count bytes from 1 and point at the last character read.
std::string line_and_column(std::string_view text, std::size_t byte) {
  const std::size_t offset = std::min(byte > 0 ? byte - 1 : 0, text.size());
  const std::size_t line = 1 + static_cast<std::size_t>(std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(offset), '\n'));
  const std::size_t line_start = text.rfind('\n', offset == 0 ? std::string_view::npos : offset - 1);
  const std::size_t column = offset - (line_start == std::string_view::npos || offset == 0 ? 0 : line_start + 1) + 1;
  return "line " + std::to_string(line) + ":" + std::to_string(column);
}

// "[json.exception.parse_error.101] parse error at line 3, column 7: syntax error ..." -> "syntax error ...":
// the position is already in the InputError location.
std::string strip_nlohmann_prefix(const std::string& what) {
  const std::size_t column = what.find(", column ");
  if (column != std::string::npos) {
    const std::size_t colon = what.find(": ", column);
    if (colon != std::string::npos) return what.substr(colon + 2);
  }
  const std::size_t bracket = what.find("] ");
  return bracket == std::string::npos ? what : what.substr(bracket + 2);
}

}  // namespace

Json parse_json_text(std::string_view text, const std::filesystem::path& file) {
  try {
    Json document = Json::parse(text.begin(), text.end());
    DuplicateKeyFinder duplicates;
    Json::sax_parse(text.begin(), text.end(), &duplicates);
    if (duplicates.found)
      throw InputError(file, duplicates.duplicate_pointer,
                       "duplicate key '" + duplicates.duplicate_key + "' (JSON parsers keep only one of the values)");
    return document;
  } catch (const nlohmann::json::parse_error& e) {
    throw InputError(file, line_and_column(text, e.byte), "JSON " + strip_nlohmann_prefix(e.what()));
  } catch (const nlohmann::json::exception& e) {
    ErrorLocator locator;
    Json::sax_parse(text.begin(), text.end(), &locator);
    // Point at the first character of the offending number rather than its last.
    const std::size_t start = locator.byte >= locator.token.size() ? locator.byte - locator.token.size() + 1 : 0;
    const std::string message = e.id == 406 ? "number " + locator.token + " is out of range"
                                            : "JSON " + strip_nlohmann_prefix(e.what());
    throw InputError(file, line_and_column(text, start), message);
  }
}

void JsonNode::fail(const std::string& message) const { throw InputError(*file_, pointer_, message); }

void JsonNode::expect_object(std::initializer_list<std::string_view> allowed) const {
  if (!value_->is_object()) fail("expected an object, found " + describe_type(*value_));
  for (const auto& [key, value] : value_->items()) {
    if (key == "comment") continue;
    if (std::find(allowed.begin(), allowed.end(), key) != allowed.end()) continue;
    std::string_view closest;
    std::size_t best = std::numeric_limits<std::size_t>::max();
    for (std::string_view candidate : allowed) {
      const std::size_t d = edit_distance(key, candidate);
      if (d < best) best = d, closest = candidate;
    }
    std::string message = "unknown key '" + key + "'";
    // A suggestion is only useful when it is plausibly a typo: at most a third of the letters differ.
    if (!closest.empty() && best <= std::max<std::size_t>(1, closest.size() / 3))
      message += " (did you mean '" + std::string(closest) + "'?)";
    else if (allowed.size() > 0) {
      message += " (expected one of:";
      for (std::string_view candidate : allowed) message.append(" ").append(candidate);
      message += ")";
    }
    JsonNode(value, pointer_ + "/" + escape_pointer_token(key), *file_).fail(message);
  }
}

bool JsonNode::has(std::string_view key) const {
  return value_->is_object() && value_->contains(std::string(key));
}

JsonNode JsonNode::member(std::string_view key) const {
  if (!value_->is_object()) fail("expected an object, found " + describe_type(*value_));
  const auto it = value_->find(std::string(key));
  if (it == value_->end()) fail("missing required key '" + std::string(key) + "'");
  return JsonNode(*it, pointer_ + "/" + escape_pointer_token(key), *file_);
}

std::optional<JsonNode> JsonNode::optional_member(std::string_view key) const {
  if (!has(key)) return std::nullopt;
  return member(key);
}

std::size_t JsonNode::expect_array() const {
  if (!value_->is_array()) fail("expected an array, found " + describe_type(*value_));
  return value_->size();
}

std::size_t JsonNode::expect_array_of_size(std::size_t n) const {
  if (!value_->is_array() || value_->size() != n)
    fail("expected an array of " + std::to_string(n) + " numbers, found " +
         (value_->is_array() ? "an array of " + std::to_string(value_->size()) : describe_type(*value_)));
  return n;
}

JsonNode JsonNode::element(std::size_t index) const {
  return JsonNode((*value_)[index], pointer_ + "/" + std::to_string(index), *file_);
}

std::string JsonNode::as_string() const {
  if (!value_->is_string()) fail("expected a string, found " + describe_type(*value_));
  return value_->get<std::string>();
}

double JsonNode::as_double() const {
  if (!value_->is_number()) fail("expected a number, found " + describe_type(*value_));
  const double v = value_->get<double>();
  if (!std::isfinite(v)) fail("number is not finite");  // unreachable from text, kept for programmatic JSON
  return v;
}

float JsonNode::as_float() const {
  const double v = as_double();
  if (!std::isfinite(static_cast<float>(v))) fail("number " + value_->dump() + " is out of float range");
  return static_cast<float>(v);
}

std::int64_t JsonNode::as_integer(std::int64_t lo, std::int64_t hi) const {
  if (!value_->is_number_integer()) fail("expected an integer, found " + describe_type(*value_));
  const bool too_big = value_->is_number_unsigned() &&
                       value_->get<std::uint64_t>() > static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max());
  const std::int64_t v = too_big ? std::numeric_limits<std::int64_t>::max() : value_->get<std::int64_t>();
  if (too_big || v < lo || v > hi)
    fail("value " + value_->dump() + " out of range [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  return v;
}

std::uint64_t JsonNode::as_unsigned() const {
  if (!value_->is_number_integer()) fail("expected a non-negative integer, found " + describe_type(*value_));
  if (!value_->is_number_unsigned() && value_->get<std::int64_t>() < 0)
    fail("expected a non-negative integer, found " + value_->dump());
  return value_->get<std::uint64_t>();
}

glm::dvec3 JsonNode::as_dvec3() const {
  expect_array_of_size(3);
  return {element(0).as_double(), element(1).as_double(), element(2).as_double()};
}

glm::vec3 JsonNode::as_vec3() const {
  expect_array_of_size(3);
  return {element(0).as_float(), element(1).as_float(), element(2).as_float()};
}

glm::vec3 JsonNode::as_color() const {
  if (value_->is_number()) {
    const float grey = as_float();
    if (grey < 0.0f) fail("colour must be non-negative, got " + value_->dump());
    return glm::vec3(grey);
  }
  if (!value_->is_array()) fail("expected a colour ([r, g, b] or a number), found " + describe_type(*value_));
  const glm::vec3 c = as_vec3();
  for (int k = 0; k < 3; ++k)
    if (c[k] < 0.0f) element(static_cast<std::size_t>(k)).fail("colour components must be non-negative");
  return c;
}

}  // namespace twinray
