// --junit FILE: JUnit XML as CI systems read it. One <testsuite> (the suite) in <testsuites>; one <testcase>
// per check, classname "twinray.SUITE.CATEGORY"; a fail is a <failure>, a crash or timeout an <error> (the
// check could not finish), a skipped check <skipped>; the detail and reproduce line in <system-out>.

#include "harness/grade/reports.h"
#include "core/util/text_safety.h"

#include <fmt/core.h>

namespace twinray::grade {

namespace {

std::string attribute(std::string_view name, std::string_view value) {
  return fmt::format(" {}=\"{}\"", name, xml_escape(value));
}

}  // namespace

std::string junit_xml(const Scorecard& card) {
  std::size_t failures = 0, errors = 0, skipped = 0;
  for (const CheckResult& c : card.checks) {
    failures += c.outcome == Outcome::Fail ? 1 : 0;
    errors += c.outcome == Outcome::Crash || c.outcome == Outcome::Timeout ? 1 : 0;
    skipped += c.outcome == Outcome::Skipped ? 1 : 0;
  }
  const std::string counts = fmt::format(" tests=\"{}\" failures=\"{}\" errors=\"{}\" skipped=\"{}\" time=\"{:.3f}\"",
                                         card.checks.size(), failures, errors, skipped, card.seconds);
  std::string x = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  x += "<testsuites" + attribute("name", "twinray grade") + counts + ">\n";
  x += "  <testsuite" + attribute("name", card.suite) + counts + ">\n";
  x += "    <properties>\n";
  for (const auto& [name, value] :
       {std::pair<std::string, std::string>{"plugin", card.plugin},
        {"plugin_name", card.plugin_name},
        {"suite_path", card.suite_path},
        {"score", format_points(card.score())},
        {"max_score", format_points(card.max_score())},
        {"passed", card.passed() ? "true" : "false"}})
    x += "      <property" + attribute("name", name) + attribute("value", value) + "/>\n";
  x += "    </properties>\n";
  for (const CheckResult& c : card.checks) {
    x += "    <testcase" + attribute("name", c.name) +
         attribute("classname", fmt::format("twinray.{}.{}", card.suite, to_string(c.category))) +
         fmt::format(" time=\"{:.3f}\"", c.seconds) + ">\n";
    const std::string message = (c.required ? "" : "(not required) ") + c.detail;
    switch (c.outcome) {
      case Outcome::Fail:
        x += "      <failure" + attribute("message", message) + attribute("type", "fail") + ">" +
             xml_escape(c.reproduce.empty() ? c.detail : "reproduce: " + c.reproduce) + "</failure>\n";
        break;
      case Outcome::Crash:
      case Outcome::Timeout:
        x += "      <error" + attribute("message", message) + attribute("type", to_string(c.outcome)) + ">" +
             xml_escape(c.reproduce.empty() ? c.detail : "reproduce: " + c.reproduce) + "</error>\n";
        break;
      case Outcome::Skipped: x += "      <skipped" + attribute("message", c.detail) + "/>\n"; break;
      case Outcome::Pass: break;
    }
    std::string out = fmt::format("{} {}/{} {}\n{}\n", to_string(c.outcome), format_points(c.points),
                                  format_points(c.max_points), to_string(c.category), c.detail);
    if (!c.reproduce.empty()) out += "reproduce: " + c.reproduce + "\n";
    x += "      <system-out>" + xml_escape(out) + "</system-out>\n";
    if (c.figures.contains("plugin_output"))
      x += "      <system-err>" + xml_escape(c.figures["plugin_output"].get<std::string>()) + "</system-err>\n";
    x += "    </testcase>\n";
  }
  x += "  </testsuite>\n</testsuites>\n";
  return x;
}

}  // namespace twinray::grade
