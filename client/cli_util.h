#pragma once

#include <google/protobuf/message.h>

#include <map>
#include <string>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "fenestra/v1/service.pb.h"

namespace fenestra {

// Prints "error: <message>" to stderr and ends the command with exit code 1.
[[noreturn]] void Fail(const absl::Status& status);

// Returns the value, or Fail()s with its status.
template <typename T>
T ValueOrFail(absl::StatusOr<T> value) {
  if (!value.ok()) Fail(value.status());
  return *std::move(value);
}

// Parses "alpha=0.5,width=0.12" into name -> value.
absl::StatusOr<std::map<std::string, double>> ParseDesignValues(const std::string& text);

// A file's bytes; NotFound "<path>: cannot open (<reason>)".
absl::StatusOr<std::string> ReadFileBytes(const std::string& path);

// How ToJson lays a message out (protobuf's JSON mapping in every case).
enum class JsonLayout {
  kLine,        // one line, lowerCamelCase names, default values left out (event streams)
  kIndented,    // indented, otherwise as kLine (--json of show, list and result)
  kResultFile,  // indented, proto field names, every field (result files)
};

// The message as JSON.
std::string ToJson(const google::protobuf::Message& message, JsonLayout layout);

// Writes the message as JSON (kResultFile layout) to `path`, atomically.
absl::Status WriteJsonFile(const std::string& path, const google::protobuf::Message& message);

// A state's name as the client prints it: "computing", "ready", "queued", "succeeded", ...
// "34.8300° S, 56.0000° W": degrees without sign, the hemisphere's letter after them.
std::string FormatLocation(double latitude_deg, double longitude_deg);

std::string StateName(v1::SiteState state);
std::string StateName(v1::JobState state);

// Succeeded, failed, cancelled or interrupted: the job will not change any more.
bool IsFinalState(v1::JobState state);

}  // namespace fenestra
