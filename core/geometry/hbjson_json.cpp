#include "core/geometry/hbjson_json.h"

#include <google/protobuf/util/json_util.h>

#include <cmath>

#include "absl/strings/str_cat.h"
#include "core/common/text.h"

namespace fenestra::hbjson {
namespace {

using google::protobuf::Value;

// Honeybee's identifiers hold at most 100 characters.
constexpr size_t kMaxIdentifierBytes = 100;

// The deepest nesting of arrays and objects in `text`, counting up to `limit` + 1 (brackets
// inside strings do not count).
int Depth(std::string_view text, int limit) {
  int depth = 0, deepest = 0;
  bool in_string = false;
  for (size_t i = 0; i < text.size() && deepest <= limit; ++i) {
    const char c = text[i];
    if (in_string) {
      if (c == '\\') {
        ++i;
      } else if (c == '"') {
        in_string = false;
      }
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      deepest = std::max(deepest, ++depth);
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
  return deepest;
}

}  // namespace

absl::StatusOr<Value> ParseJson(std::string_view text, const std::string& source,
                                size_t max_bytes) {
  if (text.size() > max_bytes) {
    return absl::InvalidArgumentError(absl::StrCat(source, ": the model is ", text.size(),
                                                   " bytes, more than the ", max_bytes, " taken"));
  }
  if (Depth(text, kMaxJsonDepth) > kMaxJsonDepth) {
    return absl::InvalidArgumentError(
        absl::StrCat(source, ": arrays and objects nest deeper than ", kMaxJsonDepth, " levels"));
  }
  Value value;
  const auto status = google::protobuf::util::JsonStringToMessage(
      google::protobuf::StringPiece(text.data(), text.size()), &value);
  if (!status.ok()) {
    // Protobuf's first line says why; the next ones quote the text, left out
    const std::string message(status.message());
    return absl::InvalidArgumentError(absl::StrCat(
        source, ": malformed JSON: ", QuoteText(message.substr(0, message.find('\n')), 256)));
  }
  return value;
}

absl::Status Json::Error(std::string_view reason) const {
  const absl::string_view why(reason.data(), reason.size());
  if (path_.empty()) return absl::InvalidArgumentError(absl::StrCat(*source_, ": ", why));
  return absl::InvalidArgumentError(absl::StrCat(*source_, ": ", path_, ": ", why));
}

std::string Json::TypeName() const {
  switch (value_->kind_case()) {
    case Value::kNullValue:
      return "null";
    case Value::kNumberValue:
      return "a number";
    case Value::kStringValue:
      return "a string";
    case Value::kBoolValue:
      return "true or false";
    case Value::kStructValue:
      return "an object";
    case Value::kListValue:
      return "an array";
    default:
      return "nothing";
  }
}

std::string Json::ChildPath(std::string_view key) const {
  const absl::string_view k(key.data(), key.size());
  return path_.empty() ? std::string(k) : absl::StrCat(path_, ".", k);
}

Json Json::Child(const Value& value, std::string_view key) const {
  return Json(value, ChildPath(key), *source_);
}

absl::StatusOr<std::optional<Json>> Json::Find(std::string_view key) const {
  if (value_->kind_case() != Value::kStructValue) {
    return Error(absl::StrCat("must be an object, got ", TypeName()));
  }
  const auto& fields = value_->struct_value().fields();
  const auto it = fields.find(std::string(key));
  if (it == fields.end() || it->second.kind_case() == Value::kNullValue) return std::nullopt;
  return Child(it->second, key);
}

absl::StatusOr<Json> Json::Get(std::string_view key) const {
  absl::StatusOr<std::optional<Json>> found = Find(key);
  if (!found.ok()) return found.status();
  if (!found->has_value()) {
    return Json(*value_, ChildPath(key), *source_).Error("is required");
  }
  return **found;
}

absl::StatusOr<std::string> Json::String() const {
  if (value_->kind_case() != Value::kStringValue) {
    return Error(absl::StrCat("must be a string, got ", TypeName()));
  }
  return value_->string_value();
}

absl::StatusOr<double> Json::Number() const {
  if (value_->kind_case() != Value::kNumberValue) {
    return Error(absl::StrCat("must be a number, got ", TypeName()));
  }
  const double x = value_->number_value();
  if (!std::isfinite(x)) return Error("must be a finite number");
  return x;
}

absl::StatusOr<bool> Json::Bool() const {
  if (value_->kind_case() != Value::kBoolValue) {
    return Error(absl::StrCat("must be true or false, got ", TypeName()));
  }
  return value_->bool_value();
}

absl::StatusOr<std::vector<Json>> Json::List(size_t max, std::string_view what) const {
  if (value_->kind_case() != Value::kListValue) {
    return Error(absl::StrCat("must be an array, got ", TypeName()));
  }
  const auto& values = value_->list_value().values();
  if (static_cast<size_t>(values.size()) > max) {
    return Error(absl::StrCat("holds ", values.size(), " ",
                              absl::string_view(what.data(), what.size()), ", more than the ", max,
                              " taken"));
  }
  std::vector<Json> out;
  out.reserve(static_cast<size_t>(values.size()));
  for (int i = 0; i < values.size(); ++i) {
    out.emplace_back(values.Get(i), absl::StrCat(path_, "[", i, "]"), *source_);
  }
  return out;
}

absl::StatusOr<std::vector<Json>> Json::ListOf(std::string_view key, size_t max,
                                               std::string_view what) const {
  absl::StatusOr<std::optional<Json>> found = Find(key);
  if (!found.ok()) return found.status();
  if (!found->has_value()) return std::vector<Json>{};
  return (*found)->List(max, what);
}

absl::StatusOr<std::string> Json::StringOr(std::string_view key, std::string fallback) const {
  absl::StatusOr<std::optional<Json>> found = Find(key);
  if (!found.ok()) return found.status();
  if (!found->has_value()) return fallback;
  return (*found)->String();
}

absl::StatusOr<double> Json::NumberOr(std::string_view key, double fallback) const {
  absl::StatusOr<std::optional<Json>> found = Find(key);
  if (!found.ok()) return found.status();
  if (!found->has_value()) return fallback;
  return (*found)->Number();
}

absl::StatusOr<bool> Json::BoolOr(std::string_view key, bool fallback) const {
  absl::StatusOr<std::optional<Json>> found = Find(key);
  if (!found.ok()) return found.status();
  if (!found->has_value()) return fallback;
  return (*found)->Bool();
}

Json Json::At(size_t i) const {
  return Json(value_->list_value().values(static_cast<int>(i)), absl::StrCat(path_, "[", i, "]"),
              *source_);
}

absl::StatusOr<Vec3d> Json::Point(double scale) const {
  if (value_->kind_case() != Value::kListValue || value_->list_value().values_size() != 3) {
    return Error(absl::StrCat("must be a point: an array of 3 numbers, got ", TypeName()));
  }
  double c[3];
  for (int i = 0; i < 3; ++i) {
    const Value& v = value_->list_value().values(i);
    if (v.kind_case() != Value::kNumberValue || !std::isfinite(v.number_value())) {
      return Error("must be a point: an array of 3 finite numbers");
    }
    c[i] = v.number_value() * scale;
  }
  return Vec3d{c[0], c[1], c[2]};
}

absl::StatusOr<std::vector<Vec3d>> Json::Points(double scale, size_t max) const {
  if (value_->kind_case() != Value::kListValue) {
    return Error(absl::StrCat("must be an array of points, got ", TypeName()));
  }
  const auto& values = value_->list_value().values();
  if (static_cast<size_t>(values.size()) > max) {
    return Error(absl::StrCat("holds ", values.size(), " points, more than the ", max, " taken"));
  }
  std::vector<Vec3d> points;
  points.reserve(static_cast<size_t>(values.size()));
  for (int i = 0; i < values.size(); ++i) {
    const Json point(values.Get(i), absl::StrCat(path_, "[", i, "]"), *source_);
    absl::StatusOr<Vec3d> p = point.Point(scale);
    if (!p.ok()) return p.status();
    points.push_back(*p);
  }
  return points;
}

absl::StatusOr<std::string> Identifier(const Json& where) {
  absl::StatusOr<std::string> id = where.String();
  if (!id.ok()) return id.status();
  if (id->empty()) return where.Error("must not be empty");
  const absl::Status text = CheckText(*id, "identifier", kMaxIdentifierBytes);
  if (!text.ok()) {
    const std::string message(text.message());  // "identifier: <reason>"
    return where.Error(message.substr(message.find(": ") + 2));
  }
  return id;
}

}  // namespace fenestra::hbjson
