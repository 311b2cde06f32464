#pragma once
// The scorecard in every format, each written by one module from the Scorecard alone:
//   terminal_report.cpp    the lines `twinray grade` prints
//   json_report.cpp        --json FILE (docs/grading.md lists the keys)
//   gradescope_report.cpp  --gradescope FILE, Gradescope's autograder results.json
//   junit_report.cpp       --junit FILE, JUnit XML (testsuites / testsuite / testcase)

#include "harness/grade/scorecard.h"

#include <nlohmann/json.hpp>

#include <string>

namespace twinray::grade {

// Terminal: a header, one line per check (outcome, points, category, name, detail) followed for a failure by
// an indented "reproduce:" line, and the totals.
std::string terminal_header(const Scorecard& card, std::size_t checks);
std::string terminal_check_line(const CheckResult& check);
std::string terminal_totals(const Scorecard& card);

nlohmann::json scorecard_json(const Scorecard& card);
nlohmann::json gradescope_json(const Scorecard& card);
std::string junit_xml(const Scorecard& card);

// A JSON document as file text: indented, invalid UTF-8 replaced (never thrown on), newline-terminated.
std::string json_file_text(const nlohmann::json& j);

// Points as people write them: "3", "2.5".
std::string format_points(double points);

}  // namespace twinray::grade
