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

}  // namespace fenestra
