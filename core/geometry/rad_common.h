#pragma once

// What rad_import.cpp and rad_export.cpp share: the directives' words, the number format and
// the checks of a scene's parts (rad_import.h describes the format).
#include <google/protobuf/message.h>

#include <string>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "core/geometry/scene.h"
#include "fenestra/v1/scene.pb.h"

namespace fenestra {

// The start of a directive line, and its keywords.
inline constexpr absl::string_view kRadDirective = "#@fenestra ";
inline constexpr absl::string_view kRadBlindBegin = "blind-geometry begin";
inline constexpr absl::string_view kRadBlindEnd = "blind-geometry end";
// Sensor names per `#@fenestra sensors` line, so that a line stays far below
// kMaxRadDirectiveBytes (names are at most kMaxNameBytes).
inline constexpr int kRadSensorNamesPerLine = 100;
// Deepest nesting of a directive's JSON: a window's blind's parameters are 3 levels down.
inline constexpr int kRadMaxJsonDepth = 8;
// Fenestra's glazing surface lies this far into the room from its window [m].
inline constexpr double kRadGlazingInsetM = 0.001;

// `value` with 17 significant digits: read back, the same double.
std::string RadReal(double value);

// Radiance's `bright`: the photopic luminance of (r, g, b) for its default primaries; a grey
// (r = g = b) exactly itself.
inline double RadLuminance(double r, double g, double b) {
  if (r == g && g == b) return r;
  return 0.265 * r + 0.670 * g + 0.065 * b;
}

// Builds `part`, some of a scene (materials, one window, sensors or grids, the site), by
// BuildScene, stand-ins completing what a scene needs and `part` lacks (a material, a
// window, a sensor). Errors read "<where>: <field>: <reason>"; one whose field begins with
// `field` names `label` instead ("materials[0].plastic.reflectance" -> "plastic 'paint':
// plastic.reflectance").
absl::StatusOr<Scene> BuildRadPart(v1::Scene part, const std::string& where,
                                   absl::string_view field = {}, absl::string_view label = {});

// `message` as one line of protobuf's JSON, and back (unknown fields and nesting deeper than
// kRadMaxJsonDepth are errors).
std::string RadJson(const google::protobuf::Message& message);
absl::Status ParseRadJson(absl::string_view json, google::protobuf::Message* message);

}  // namespace fenestra
