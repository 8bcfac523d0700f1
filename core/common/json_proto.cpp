#include "core/common/json_proto.h"

#include <google/protobuf/util/json_util.h>

#include <fstream>
#include <sstream>

#include "absl/strings/str_cat.h"

namespace fenestra {

absl::Status ReadJsonProtoFile(const std::string& path, const char* what,
                               google::protobuf::Message* message) {
  std::ifstream in(path);
  if (!in) return absl::NotFoundError(absl::StrCat(path, ": cannot open ", what, " file"));
  std::stringstream text;
  text << in.rdbuf();
  return ParseJsonProto(text.str(), absl::StrCat(path, ": malformed ", what), message);
}

absl::Status ParseJsonProto(const std::string& json, const std::string& context,
                            google::protobuf::Message* message) {
  google::protobuf::util::JsonParseOptions options;
  options.ignore_unknown_fields = false;
  const auto status = google::protobuf::util::JsonStringToMessage(json, message, options);
  if (!status.ok()) {
    return absl::InvalidArgumentError(absl::StrCat(context, ": ", std::string(status.message())));
  }
  return absl::OkStatus();
}

}  // namespace fenestra
