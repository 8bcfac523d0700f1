#pragma once

#include <google/protobuf/message.h>

#include <string>

#include "absl/status/status.h"

namespace fenestra {

// Reads a JSON file (protobuf's JSON mapping) into `message`; unknown fields are errors.
// NotFound "<path>: cannot open <what> file", or InvalidArgument "<path>: malformed <what>:
// <reason>".
absl::Status ReadJsonProtoFile(const std::string& path, const char* what,
                               google::protobuf::Message* message);

// Parses `json` (protobuf's JSON mapping; unknown fields are errors) into `message`;
// InvalidArgument "<context>: <reason>".
absl::Status ParseJsonProto(const std::string& json, const std::string& context,
                            google::protobuf::Message* message);

}  // namespace fenestra
