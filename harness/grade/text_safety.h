#pragma once
// Text that reaches a file other programs parse must be valid there, whatever a plugin printed or named:
// valid UTF-8 for JSON (nlohmann refuses to dump anything else), and in XML 1.0 also none of the control
// characters the format forbids.

#include <string>
#include <string_view>

namespace twinray::grade {

// `text` with every invalid UTF-8 sequence replaced by U+FFFD.
std::string valid_utf8(std::string_view text);

// Valid UTF-8, the five XML special characters escaped, and the control characters XML 1.0 forbids (all
// below 0x20 except tab, newline and carriage return) replaced by U+FFFD.
std::string xml_escape(std::string_view text);

}  // namespace twinray::grade
