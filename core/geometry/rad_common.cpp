#include "core/geometry/rad_common.h"

#include <google/protobuf/util/json_util.h>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"

namespace fenestra {

std::string RadReal(double value) { return absl::StrFormat("%.17g", value); }

absl::StatusOr<Scene> BuildRadPart(v1::Scene part, const std::string& where,
                                   absl::string_view field, absl::string_view label) {
  if (part.materials_size() == 0) {
    v1::Material* stand_in = part.add_materials();
    stand_in->set_name("stand-in");
    stand_in->set_reflectance(0.5);
  }
  if (!part.has_window() && part.windows_size() == 0) {
    v1::Window* w = part.mutable_window();
    w->mutable_outward_normal()->set_y(1);
    w->mutable_up()->set_z(1);
    w->set_width_m(1);
    w->set_height_m(1);
  }
  if (part.sensors_size() == 0 && part.sensor_grids_size() == 0) {
    v1::Sensor* s = part.add_sensors();
    s->mutable_position()->set_y(-1);
    s->mutable_direction()->set_z(1);
  }
  absl::StatusOr<Scene> scene = BuildScene(part, where);
  if (scene.ok() || field.empty()) return scene;
  // "<where>: <field>.<rest>: reason" -> "<where>: <label>: <rest>: reason"
  std::string message(scene.status().message());
  const std::string start = absl::StrCat(where, ": ", field);
  if (message.rfind(start, 0) == 0) {
    std::string rest = message.substr(start.size());
    if (!rest.empty() && rest[0] == '.') rest = absl::StrCat(": ", rest.substr(1));
    message = absl::StrCat(where, ": ", label, rest);
  }
  return absl::Status(scene.status().code(), message);
}

std::string RadJson(const google::protobuf::Message& message) {
  std::string json;
  // Only an unset required or unknown field fails, which proto3 messages do not have
  (void)google::protobuf::util::MessageToJsonString(message, &json);
  return json;
}

absl::Status ParseRadJson(absl::string_view json, google::protobuf::Message* message) {
  // Nesting bounded first: protobuf's parser takes very long over deep lists
  int depth = 0;
  bool in_string = false;
  for (size_t i = 0; i < json.size(); ++i) {
    const char c = json[i];
    if (in_string) {
      if (c == '\\') ++i;
      if (c == '"') in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '{' || c == '[') {
      if (++depth > kRadMaxJsonDepth) {
        return absl::InvalidArgumentError(
            absl::StrCat("nested deeper than ", kRadMaxJsonDepth, " levels"));
      }
    } else if (c == '}' || c == ']') {
      --depth;
    }
  }
  google::protobuf::util::JsonParseOptions options;
  options.ignore_unknown_fields = false;
  const auto status = google::protobuf::util::JsonStringToMessage(
      google::protobuf::StringPiece(json.data(), json.size()), message, options);
  if (status.ok()) return absl::OkStatus();
  return absl::InvalidArgumentError(std::string(status.message()));
}

}  // namespace fenestra
