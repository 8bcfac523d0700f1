#include "client/cli_util.h"

#include <fmt/core.h>
#include <google/protobuf/util/json_util.h>

#include <CLI/CLI.hpp>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include "absl/strings/ascii.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "absl/strings/strip.h"
#include "core/common/atomic_file.h"

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

absl::StatusOr<std::string> ReadFileBytes(const std::string& path) {
  std::error_code error;
  if (std::filesystem::is_directory(path, error)) {
    return absl::NotFoundError(absl::StrCat(path, ": cannot open (a directory)"));
  }
  std::ifstream in(path, std::ios::binary);
  if (!in)
    return absl::NotFoundError(absl::StrCat(path, ": cannot open (", std::strerror(errno), ")"));
  std::stringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

std::string ToJson(const google::protobuf::Message& message, JsonLayout layout) {
  google::protobuf::util::JsonPrintOptions options;
  options.add_whitespace = layout != JsonLayout::kLine;
  options.always_print_primitive_fields = layout == JsonLayout::kResultFile;
  options.preserve_proto_field_names = layout == JsonLayout::kResultFile;
  std::string json;
  // Fails only for Any fields of unknown types, which no Fenestra message has
  (void)google::protobuf::util::MessageToJsonString(message, &json, options);
  while (!json.empty() && json.back() == '\n') json.pop_back();
  return json;
}

absl::Status WriteJsonFile(const std::string& path, const google::protobuf::Message& message) {
  const std::string json = ToJson(message, JsonLayout::kResultFile);
  return WriteFileAtomically(path, [&](std::ostream& out) {
    out << json << '\n';
    return absl::OkStatus();
  });
}

namespace {

// "SITE_STATE_READY" -> "ready"; a value this client does not know -> "unknown (7)"
std::string LowerStateName(const std::string& enum_name, int value) {
  const size_t prefix = enum_name.find("STATE_");
  if (prefix == std::string::npos) return absl::StrCat("unknown (", value, ")");
  return absl::AsciiStrToLower(enum_name.substr(prefix + 6));
}

}  // namespace

std::string FormatLocation(double latitude_deg, double longitude_deg) {
  return fmt::format("{:.4f}° {}, {:.4f}° {}", std::abs(latitude_deg), latitude_deg < 0 ? 'S' : 'N',
                     std::abs(longitude_deg), longitude_deg < 0 ? 'W' : 'E');
}

std::string StateName(v1::SiteState state) {
  return LowerStateName(v1::SiteState_Name(state), state);
}
std::string StateName(v1::JobState state) {
  return LowerStateName(v1::JobState_Name(state), state);
}

bool IsFinalState(v1::JobState state) {
  return state != v1::JOB_STATE_QUEUED && state != v1::JOB_STATE_RUNNING &&
         state != v1::JOB_STATE_UNSPECIFIED;
}

}  // namespace fenestra
