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

// JSON allows an object to repeat a key and nlohmann keeps one of the values, so a scene with two
// "radius" keys would silently render one of them. The parser's callback sees every key as it is read:
// this check tracks the open containers (for the JSON pointer of the repeat) and throws at the first
// repeated key, in the same single pass that builds the document. Hashing keeps objects with very many
// keys (fuzzed input) linear.
class DuplicateKeyCheck {
 public:
  explicit DuplicateKeyCheck(const std::filesystem::path& file) : file_(file) {}

  bool operator()(int /*depth*/, Json::parse_event_t event, Json& parsed) {
    switch (event) {
      case Json::parse_event_t::object_start:
        value_starts();
        open_.emplace_back();
        break;
      case Json::parse_event_t::array_start:
        value_starts();
        open_.emplace_back().is_array = true;
        break;
      case Json::parse_event_t::object_end:
      case Json::parse_event_t::array_end:
        open_.pop_back();
        break;
      case Json::parse_event_t::value:
        value_starts();
        break;
      case Json::parse_event_t::key: {
        const std::string& key = parsed.get_ref<const std::string&>();
        Container& object = open_.back();
        object.child_token = escape_pointer_token(key);
        if (!object.keys.insert(key).second) {
          std::string pointer;
          for (const Container& c : open_) pointer += "/" + c.child_token;
          throw InputError(file_, pointer, "duplicate key '" + key + "' (JSON parsers keep only one of the values)");
        }
        break;
      }
    }
    return true;  // keep every value
  }

 private:
  struct Container {
    bool is_array = false;
    std::size_t next_index = 0;
    std::unordered_set<std::string> keys;
    std::string child_token;  // pointer token of the member or element being read
  };

  void value_starts() {
    if (!open_.empty() && open_.back().is_array) open_.back().child_token = std::to_string(open_.back().next_index++);
  }

  const std::filesystem::path& file_;
  std::vector<Container> open_;
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
    // nlohmann copies the callback (a std::function): the check's state lives here, the callback refers to it.
    DuplicateKeyCheck duplicates(file);
    return Json::parse(text.begin(), text.end(),
                       [&duplicates](int depth, Json::parse_event_t event, Json& parsed) {
                         return duplicates(depth, event, parsed);
                       });
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

bool JsonNode::as_bool() const {
  if (!value_->is_boolean()) fail("expected true or false, found " + describe_type(*value_));
  return value_->get<bool>();
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
