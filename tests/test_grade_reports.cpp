// The scorecard formats (harness/grade/reports.h), each checked against its own rules: JSON keys of the
// contract, Gradescope's results.json against a schema of Gradescope's documented format (jsonschema), JUnit
// XML against an XSD of the common JUnit format (xmllint), with the strings a plugin can inject.

#include "harness/grade/reports.h"
#include "core/util/text_safety.h"
#include "tests/format_validators.h"

#include <gtest/gtest.h>

#include <fstream>

namespace twinray::grade {
namespace {

using testing::quoted;

// One check of every outcome, with text that is hard to carry: XML specials, quotes, control characters,
// invalid UTF-8 (a plugin's name or output can contain anything).
Scorecard sample_scorecard() {
  Scorecard card;
  card.plugin = "/tmp/lib<weird> & \"name\".so";
  card.plugin_name = "plugin:bad\xff\xfe name";
  card.suite = "t";
  card.suite_path = "/suites/t/manifest.json";
  card.claims.counts_traversal = true;
  card.seconds = 12.25;
  const Outcome outcomes[] = {Outcome::Pass, Outcome::Fail, Outcome::Crash, Outcome::Timeout, Outcome::Skipped};
  const Category categories[] = {Category::Build, Category::ClosestHit, Category::AxisAligned, Category::AxisAligned,
                                 Category::ThreadSafety};
  for (int i = 0; i < 5; ++i) {
    CheckResult c;
    c.name = "check-" + std::to_string(i);
    c.category = categories[i];
    c.outcome = outcomes[i];
    c.max_points = 2.0;
    c.points = c.outcome == Outcome::Pass ? 2.0 : 0.0;
    c.required = i != 3;
    c.visibility = i == 4 ? Visibility::Hidden : Visibility::Visible;
    c.detail = "detail <" + std::to_string(i) + "> & 'quotes' \"too\"\x01\x1b[31m red \xc3\x28";
    if (c.failed()) c.reproduce = "twinray trace x --ray '0x1p+0 0 0 1 0 0 0 inf'";
    c.seconds = 0.5 * i;
    c.figures = {{"rays", 100 * i}};
    if (c.outcome == Outcome::Crash) c.figures["plugin_output"] = "printf debugging\x07 <before> the crash\xff\n";
    card.checks.push_back(c);
  }
  card.performance["perf"] = {{"rays_per_second", {{"plugin", 1.0e6}}}};
  return card;
}

std::filesystem::path write(const std::string& name, const std::string& text) {
  const std::filesystem::path p = testing::scratch_dir("reports") / name;
  std::ofstream(p, std::ios::binary) << text;
  return p;
}

TEST(GradeReports, JsonHasTheContractKeys) {
  const Scorecard card = sample_scorecard();
  const nlohmann::json j = nlohmann::json::parse(json_file_text(scorecard_json(card)));
  for (const char* key : {"score", "max_score", "passed", "plugin", "suite", "checks", "performance"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_EQ(j.at("score").get<double>(), 2.0);
  EXPECT_EQ(j.at("max_score").get<double>(), 10.0);
  EXPECT_FALSE(j.at("passed").get<bool>());  // check-1 and check-2 are required failures
  ASSERT_EQ(j.at("checks").size(), 5u);
  for (const auto& c : j.at("checks"))
    for (const char* key : {"name", "category", "outcome", "points", "max_points", "detail", "reproduce"})
      EXPECT_TRUE(c.contains(key)) << key;
  EXPECT_EQ(j.at("checks")[2].at("outcome"), "crash");
  EXPECT_EQ(j.at("checks")[2].at("category"), "axis-aligned");
  EXPECT_TRUE(j.at("checks")[0].at("reproduce").is_null());
  EXPECT_EQ(j.at("counts").at("timeout"), 1);
  // Invalid UTF-8 is replaced, never thrown on.
  EXPECT_NE(j.at("plugin_name").get<std::string>().find("\xEF\xBF\xBD"), std::string::npos);
}

TEST(GradeReports, GradescopeFileValidatesAgainstGradescopesFormat) {
  const Scorecard card = sample_scorecard();
  const nlohmann::json j = gradescope_json(card);
  const auto file = write("results.json", json_file_text(j));
  const testing::CommandResult r = testing::validate_gradescope(file);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  ASSERT_EQ(j.at("tests").size(), 5u);
  EXPECT_EQ(j.at("score").get<double>(), 2.0);
  EXPECT_EQ(j.at("tests")[0].at("status"), "passed");
  EXPECT_EQ(j.at("tests")[1].at("status"), "failed");
  EXPECT_FALSE(j.at("tests")[4].contains("status"));  // skipped: Gradescope derives it from the score
  EXPECT_EQ(j.at("tests")[4].at("visibility"), "hidden");
  EXPECT_NE(j.at("tests")[1].at("output").get<std::string>().find("twinray trace"), std::string::npos);
  EXPECT_NE(j.at("tests")[2].at("output").get<std::string>().find("What the plugin printed:\nprintf debugging"),
            std::string::npos);
  EXPECT_EQ(j.at("execution_time"), 13);  // whole seconds, rounded up
}

TEST(GradeReports, GradescopeSchemaRejectsWhatGradescopeWouldNot) {
  // The validator has teeth: a visibility Gradescope does not know, and a misspelt key, are refused.
  nlohmann::json j = gradescope_json(sample_scorecard());
  j["tests"][0]["visibility"] = "public";
  EXPECT_EQ(testing::validate_gradescope(write("bad-visibility.json", json_file_text(j))).exit_code, 1);
  j = gradescope_json(sample_scorecard());
  j["tests"][0]["max_points"] = 2;
  EXPECT_EQ(testing::validate_gradescope(write("bad-key.json", json_file_text(j))).exit_code, 1);
}

TEST(GradeReports, JunitFileValidatesAgainstTheJunitSchema) {
  const std::string xml = junit_xml(sample_scorecard());
  const auto file = write("junit.xml", xml);
  const testing::CommandResult r = testing::validate_junit(file);
  EXPECT_EQ(r.exit_code, 0) << r.output << "\n" << xml;
  EXPECT_NE(xml.find("tests=\"5\" failures=\"1\" errors=\"2\" skipped=\"1\""), std::string::npos) << xml;
  EXPECT_NE(xml.find("<error message="), std::string::npos);
  EXPECT_NE(xml.find("type=\"timeout\""), std::string::npos);
  EXPECT_NE(xml.find("<skipped message="), std::string::npos);
  EXPECT_NE(xml.find("<system-err>printf debugging"), std::string::npos) << xml;
  EXPECT_EQ(xml.find('\x01'), std::string::npos);  // control characters XML 1.0 forbids are gone
  // And the schema has teeth: a testcase without a name is refused.
  std::string broken = xml;
  broken.replace(broken.find("<testcase name=\"check-0\""), 24, "<testcase");
  EXPECT_NE(testing::validate_junit(write("junit-bad.xml", broken)).exit_code, 0);
}

TEST(GradeReports, TerminalLinesCarryOutcomePointsAndReproduce) {
  const Scorecard card = sample_scorecard();
  const std::string pass = terminal_check_line(card.checks[0]);
  EXPECT_EQ(pass.rfind("pass", 0), 0u) << pass;
  EXPECT_NE(pass.find("2/2"), std::string::npos);
  const std::string crash = terminal_check_line(card.checks[2]);
  EXPECT_EQ(crash.rfind("CRASH", 0), 0u) << crash;  // a required failure stands out
  EXPECT_NE(crash.find("\n         reproduce: twinray trace"), std::string::npos) << crash;
  const std::string timeout = terminal_check_line(card.checks[3]);
  EXPECT_EQ(timeout.rfind("timeout", 0), 0u) << timeout;  // not required: lower case
  const std::string totals = terminal_totals(card);
  EXPECT_NE(totals.find("score 2 / 10 (20.0%)"), std::string::npos) << totals;
  EXPECT_NE(totals.find("verdict: FAIL (2 required checks failed)"), std::string::npos) << totals;
}

TEST(GradeReports, TextSafety) {
  EXPECT_EQ(valid_utf8("plain"), "plain");
  EXPECT_EQ(valid_utf8("caf\xc3\xa9"), "caf\xc3\xa9");
  EXPECT_EQ(valid_utf8("\xff"), "\xEF\xBF\xBD");
  EXPECT_EQ(valid_utf8("\xed\xa0\x80"), "\xEF\xBF\xBD\xEF\xBF\xBD\xEF\xBF\xBD");  // a surrogate is not UTF-8
  EXPECT_EQ(valid_utf8("\xe2\x82"), "\xEF\xBF\xBD\xEF\xBF\xBD");                  // truncated sequence
  EXPECT_EQ(xml_escape("<a & 'b'>\t\"c\"\x02"), "&lt;a &amp; &apos;b&apos;&gt;\t&quot;c&quot;\xEF\xBF\xBD");
  // One line, every control character visible: C0 (newline, ESC), DEL and C1 (U+009B, a one-byte CSI).
  EXPECT_EQ(one_line("caf\xc3\xa9 ok"), "caf\xc3\xa9 ok");
  EXPECT_EQ(one_line("a\nb\x1b[2J\x7f\xc2\x9b\t"), "a\\x0ab\\x1b[2J\\x7f\\x9b\\x09");
  EXPECT_EQ(one_line("\xff"), "\xEF\xBF\xBD");
  EXPECT_EQ(format_points(3.0), "3");
  EXPECT_EQ(format_points(2.5), "2.5");
}

}  // namespace
}  // namespace twinray::grade
