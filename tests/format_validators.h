#pragma once
// Checks an output file against its format's own rules with the format's own tools, not against twinray's
// reader: JUnit XML with xmllint and an XSD of the common JUnit format, Gradescope's results.json with the
// jsonschema package and a schema written from Gradescope's documentation (both in tests/schemas/).

#include "tests/cli_runner.h"

#include <filesystem>

namespace twinray::testing {

inline CommandResult validate_junit(const std::filesystem::path& xml) {
  return run_command("xmllint --noout --schema " + quoted(source_path("tests/schemas/junit.xsd")) + " " + quoted(xml));
}

inline CommandResult validate_gradescope(const std::filesystem::path& json) {
  return run_command("python3 " + quoted(source_path("tests/schemas/validate_json.py")) + " " +
                     quoted(source_path("tests/schemas/gradescope-results.schema.json")) + " " + quoted(json));
}

}  // namespace twinray::testing
