#include "core/util/text_safety.h"

#include <cstdint>

namespace twinray {

namespace {
constexpr std::string_view kReplacement = "\xEF\xBF\xBD";  // U+FFFD

// Length of the valid UTF-8 sequence starting at s[i], or 0 (RFC 3629: no overlong forms, no surrogates, at
// most U+10FFFF).
std::size_t sequence_length(std::string_view s, std::size_t i) {
  const auto b = [&](std::size_t k) { return static_cast<std::uint8_t>(s[k]); };
  const std::uint8_t c = b(i);
  if (c < 0x80) return 1;
  // Lead byte: sequence length and the range its second byte must fall in.
  struct Lead {
    std::uint8_t first, last;
    std::size_t n;
    std::uint8_t lo, hi;
  };
  constexpr Lead kLeads[] = {{0xC2, 0xDF, 2, 0x80, 0xBF}, {0xE0, 0xE0, 3, 0xA0, 0xBF}, {0xE1, 0xEC, 3, 0x80, 0xBF},
                             {0xED, 0xED, 3, 0x80, 0x9F}, {0xEE, 0xEF, 3, 0x80, 0xBF}, {0xF0, 0xF0, 4, 0x90, 0xBF},
                             {0xF1, 0xF3, 4, 0x80, 0xBF}, {0xF4, 0xF4, 4, 0x80, 0x8F}};
  std::size_t n = 0;
  std::uint8_t lo = 0, hi = 0;
  for (const Lead& l : kLeads)
    if (c >= l.first && c <= l.last) {
      n = l.n;
      lo = l.lo;
      hi = l.hi;
    }
  if (n == 0) return 0;
  if (i + n > s.size()) return 0;
  if (b(i + 1) < lo || b(i + 1) > hi) return 0;
  for (std::size_t k = 2; k < n; ++k)
    if (b(i + k) < 0x80 || b(i + k) > 0xBF) return 0;
  return n;
}
}  // namespace

std::string valid_utf8(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (std::size_t i = 0; i < text.size();) {
    const std::size_t n = sequence_length(text, i);
    if (n == 0) {
      out += kReplacement;
      ++i;
    } else {
      out.append(text.substr(i, n));
      i += n;
    }
  }
  return out;
}

std::string xml_escape(std::string_view text) {
  const std::string utf8 = valid_utf8(text);
  std::string out;
  out.reserve(utf8.size());
  for (const char c : utf8) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&apos;"; break;
      default:
        if (static_cast<unsigned char>(c) < 0x20 && c != '\t' && c != '\n' && c != '\r') out += kReplacement;
        else out += c;
    }
  }
  return out;
}

namespace {

// Valid UTF-8 with every control character but those in `kept` written as a visible \xNN.
std::string escape_controls(std::string_view text, std::string_view kept) {
  const std::string utf8 = valid_utf8(text);
  std::string out;
  out.reserve(utf8.size());
  for (std::size_t i = 0; i < utf8.size(); ++i) {
    const auto c = static_cast<std::uint8_t>(utf8[i]);
    // C1 controls are U+0080..U+009F: 0xC2 followed by 0x80..0x9F in UTF-8.
    const bool c1 = c == 0xC2 && i + 1 < utf8.size() && static_cast<std::uint8_t>(utf8[i + 1]) <= 0x9F;
    if ((c < 0x20 && kept.find(static_cast<char>(c)) == std::string_view::npos) || c == 0x7F || c1) {
      const unsigned code = c1 ? static_cast<std::uint8_t>(utf8[++i]) : c;
      constexpr char kHex[] = "0123456789abcdef";
      out += "\\x";
      out += kHex[code >> 4];
      out += kHex[code & 0xF];
    } else {
      out += utf8[i];
    }
  }
  return out;
}

}  // namespace

std::string one_line(std::string_view text) { return escape_controls(text, ""); }

std::string printable_lines(std::string_view text) { return escape_controls(text, "\n\t"); }

}  // namespace twinray
