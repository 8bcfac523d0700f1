#include "client/cli_util.h"

#include <CLI/CLI.hpp>
#include <iostream>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "absl/strings/strip.h"

namespace fenestra {

void Fail(const absl::Status& status) {
  std::cerr << "error: " << status.message() << std::endl;
  throw CLI::RuntimeError(1);
}

absl::StatusOr<std::map<std::string, double>> ParseDesignValues(const std::string& text) {
  std::map<std::string, double> values;
  for (absl::string_view item : absl::StrSplit(text, ',', absl::SkipWhitespace())) {
    std::pair<absl::string_view, absl::string_view> kv = absl::StrSplit(item, '=');
    const std::string name(absl::StripAsciiWhitespace(kv.first));
    double value;
    if (name.empty() || !absl::SimpleAtod(absl::StripAsciiWhitespace(kv.second), &value)) {
      return absl::InvalidArgumentError(
          absl::StrCat("--set: expected name=value, got '", item, "'"));
    }
    values[name] = value;
  }
  return values;
}

}  // namespace fenestra
