#pragma once
// Text that reaches a file other programs parse must be valid there, whatever a plugin printed or named:
// valid UTF-8 for JSON (nlohmann refuses to dump anything else), and in XML 1.0 also none of the control
// characters the format forbids.

#include <string>
#include <string_view>

namespace twinray {

// `text` with every invalid UTF-8 sequence replaced by U+FFFD.
std::string valid_utf8(std::string_view text);

// Valid UTF-8, the five XML special characters escaped, and the control characters XML 1.0 forbids (all
// below 0x20 except tab, newline and carriage return) replaced by U+FFFD.
std::string xml_escape(std::string_view text);

// One line of plain text for a scorecard field (a check's detail, the plugin's name) that may carry a
// plugin's words (a build error message, an exception's what(), the name in its table): valid UTF-8, and every
// control character (C0, DEL and C1, among them newlines and the escape that starts a terminal's colour and
// cursor sequences) written as a visible \xNN, so what a plugin says can neither break the line nor draw a
// fake result on the grader's terminal.
std::string one_line(std::string_view text);

// What a plugin printed, for a terminal: as one_line, but newlines and tabs are kept, so its lines stay lines
// (and still cannot move the cursor, clear the screen or change colours).
std::string printable_lines(std::string_view text);

}  // namespace twinray
