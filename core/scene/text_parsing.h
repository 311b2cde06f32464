#pragma once
// Small line and number scanning helpers shared by the text formats (OBJ, ASCII PLY).
// std::from_chars does the number conversion: it is locale-independent, correctly rounded (so a float read
// straight from text equals the nearest float, not a double rounded twice), and reports overflow instead of
// silently returning infinity.

#include <charconv>
#include <cmath>
#include <cstddef>
#include <cstdlib>
#include <string>
#include <cstdint>
#include <string_view>
#include <system_error>

namespace twinray::text {

// Iterates over the lines of a text, counting them from 1, without copying; a trailing '\r' is dropped.
class LineReader {
 public:
  explicit LineReader(std::string_view text) : rest_(text) {}

  bool next(std::string_view& line) {
    if (rest_.empty()) return false;
    const std::size_t end = rest_.find('\n');
    line = rest_.substr(0, end);
    rest_ = end == std::string_view::npos ? std::string_view() : rest_.substr(end + 1);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    ++line_number_;
    return true;
  }
  std::size_t line_number() const { return line_number_; }
  // The not yet consumed bytes (the binary payload after a PLY header).
  std::string_view rest() const { return rest_; }

 private:
  std::string_view rest_;
  std::size_t line_number_ = 0;
};

inline bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }

// Removes and returns the next whitespace-separated token of `rest` (empty when none is left).
inline std::string_view next_token(std::string_view& rest) {
  std::size_t begin = 0;
  while (begin < rest.size() && is_blank(rest[begin])) ++begin;
  std::size_t end = begin;
  while (end < rest.size() && !is_blank(rest[end])) ++end;
  const std::string_view token = rest.substr(begin, end - begin);
  rest.remove_prefix(end);
  return token;
}

inline bool only_blanks(std::string_view s) {
  for (char c : s)
    if (!is_blank(c)) return false;
  return true;
}

enum class NumberStatus { Ok, Invalid, OutOfRange };

// The whole token must be the number (so "1.5abc" is Invalid). A leading '+' is accepted, as C's strtod does;
// "nan" and "inf" parse (callers reject non-finite values with a clearer message than "invalid").
template <class T>
NumberStatus parse_number(std::string_view token, T& out) {
  if (token.size() > 1 && token.front() == '+' && token[1] != '-') token.remove_prefix(1);
  const char* end = token.data() + token.size();
  const std::from_chars_result r = std::from_chars(token.data(), end, out);
  if (r.ec == std::errc::result_out_of_range) return NumberStatus::OutOfRange;
  if (r.ec != std::errc() || r.ptr != end || token.empty()) return NumberStatus::Invalid;
  return NumberStatus::Ok;
}

// A real number: like parse_number, but a value too small for T becomes zero (or a subnormal) rather than an
// error, since writers print tiny coordinates like 1e-50 and mean "zero". Overflow stays an error.
template <class T>
NumberStatus parse_real(std::string_view token, T& out) {
  const NumberStatus status = parse_number(token, out);
  if (status != NumberStatus::OutOfRange) return status;
  // Rare path: strtod tells underflow (|result| < 1) from overflow (HUGE_VAL).
  const std::string copy(token);
  const double value = std::strtod(copy.c_str(), nullptr);
  if (!(std::abs(value) < 1.0)) return NumberStatus::OutOfRange;
  out = static_cast<T>(value);
  return NumberStatus::Ok;
}

}  // namespace twinray::text
