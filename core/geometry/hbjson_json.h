// Reading a Honeybee model's JSON: the text bounded and parsed into protobuf's
// google.protobuf.Value, and a view of its values that knows where each lies in the model
// ("rooms[0].faces[3].geometry"), so that every type check names the element.
#pragma once

#include <google/protobuf/struct.pb.h>

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/common/vec3.h"

namespace fenestra::hbjson {

// Deepest nesting of arrays and objects taken: a model nests about 15 levels (a hole's
// point in a shade of an aperture of a face of a room), its energy properties a few more.
inline constexpr int kMaxJsonDepth = 64;

// Parses `text` (at most `max_bytes`, nested at most kMaxJsonDepth) into a JSON value.
// InvalidArgument "<source>: <reason>".
absl::StatusOr<google::protobuf::Value> ParseJson(std::string_view text, const std::string& source,
                                                  size_t max_bytes);

// A JSON value and where it lies: its path from the model's root and the file's name.
class Json {
 public:
  Json(const google::protobuf::Value& value, std::string path, const std::string& source)
      : value_(&value), path_(std::move(path)), source_(&source) {}

  const std::string& path() const { return path_; }
  const std::string& source() const { return *source_; }
  const google::protobuf::Value& value() const { return *value_; }

  // InvalidArgument "<source>: <path>: <reason>" (the path left out at the root).
  absl::Status Error(std::string_view reason) const;

  // The member `key` of this object: absent or null is nullopt, "is required" for Get. An
  // error when this is not an object.
  absl::StatusOr<std::optional<Json>> Find(std::string_view key) const;
  absl::StatusOr<Json> Get(std::string_view key) const;

  absl::StatusOr<std::string> String() const;
  // A finite number.
  absl::StatusOr<double> Number() const;
  absl::StatusOr<bool> Bool() const;
  // The elements of this array, at most `max` of them (`what` names them in the error).
  absl::StatusOr<std::vector<Json>> List(size_t max, std::string_view what) const;
  // Of member `key`: absent or null is an empty list.
  absl::StatusOr<std::vector<Json>> ListOf(std::string_view key, size_t max,
                                           std::string_view what) const;

  // Member `key` as a string, number or bool, with a default when absent or null.
  absl::StatusOr<std::string> StringOr(std::string_view key, std::string fallback) const;
  absl::StatusOr<double> NumberOr(std::string_view key, double fallback) const;
  absl::StatusOr<bool> BoolOr(std::string_view key, bool fallback) const;

  // Element `i` of this array (which must hold it).
  Json At(size_t i) const;

  // A point [x, y, z] of finite numbers times `scale`.
  absl::StatusOr<Vec3d> Point(double scale) const;
  // The points of this array (at most `max`), each times `scale`.
  absl::StatusOr<std::vector<Vec3d>> Points(double scale, size_t max) const;

 private:
  Json Child(const google::protobuf::Value& value, std::string_view key) const;
  std::string ChildPath(std::string_view key) const;
  std::string TypeName() const;

  const google::protobuf::Value* value_;
  std::string path_;
  const std::string* source_;
};

// Checks an identifier at `where` (1 to 100 bytes of text without control characters, as
// Honeybee's identifiers) and returns it.
absl::StatusOr<std::string> Identifier(const Json& where);

}  // namespace fenestra::hbjson
