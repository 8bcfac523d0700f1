#include "core/common/text.h"

#include <google/protobuf/descriptor.h>

#include <cstdint>
#include <string>

#include "absl/strings/escaping.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"

namespace fenestra {
namespace {

using google::protobuf::FieldDescriptor;
using google::protobuf::Message;
using google::protobuf::Reflection;

// Decodes the UTF-8 sequence at text[at]: its code point and length, or length 0 when the
// bytes are not valid UTF-8 (overlong forms, surrogates and values above U+10FFFF included).
struct CodePoint {
  uint32_t value = 0;
  size_t length = 0;
};

CodePoint DecodeUtf8(absl::string_view text, size_t at) {
  const auto byte = [&](size_t i) { return static_cast<uint8_t>(text[i]); };
  const uint8_t lead = byte(at);
  if (lead < 0x80) return {lead, 1};
  size_t length = 0;
  uint32_t value = 0, lowest = 0;
  if ((lead & 0xE0) == 0xC0) {
    length = 2, value = lead & 0x1F, lowest = 0x80;
  } else if ((lead & 0xF0) == 0xE0) {
    length = 3, value = lead & 0x0F, lowest = 0x800;
  } else if ((lead & 0xF8) == 0xF0) {
    length = 4, value = lead & 0x07, lowest = 0x10000;
  } else {
    return {};
  }
  if (at + length > text.size()) return {};
  for (size_t i = 1; i < length; ++i) {
    if ((byte(at + i) & 0xC0) != 0x80) return {};
    value = (value << 6) | (byte(at + i) & 0x3F);
  }
  if (value < lowest || value > 0x10FFFF || (value >= 0xD800 && value <= 0xDFFF)) return {};
  return {value, length};
}

// Characters that move the cursor, end a line or reorder text when printed.
bool IsControl(uint32_t c) {
  return c < 0x20 || (c >= 0x7F && c <= 0x9F) || c == 0x2028 || c == 0x2029 ||
         (c >= 0x202A && c <= 0x202E) || (c >= 0x2066 && c <= 0x2069);
}

bool IsPathField(const FieldDescriptor& field) {
  const std::string& name = field.name();
  return name == "path" || (name.size() > 5 && name.compare(name.size() - 5, 5, "_file") == 0);
}

// Where a field lies in the message checked: its parent's place, its name and its index in
// a repeated field (-1 otherwise). Written out ("a.b[3].c") only for an error, so that a large
// request's many fields cost no strings.
struct FieldPlace {
  const FieldPlace* parent;
  const FieldDescriptor* field;
  int index;
};

std::string Written(const FieldPlace* place) {
  if (place == nullptr) return "";
  std::string text = Written(place->parent);
  if (!text.empty()) text += '.';
  absl::StrAppend(&text, place->field->name());
  if (place->index >= 0) absl::StrAppend(&text, "[", place->index, "]");
  return text;
}

absl::Status CheckField(const Message& message, const FieldDescriptor& field,
                        const FieldPlace* parent);

// The fields that are set (as Reflection::ListFields has them, without its list).
absl::Status CheckMessage(const Message& message, const FieldPlace* place) {
  const Reflection& reflection = *message.GetReflection();
  const google::protobuf::Descriptor& descriptor = *message.GetDescriptor();
  for (int i = 0; i < descriptor.field_count(); ++i) {
    const FieldDescriptor& field = *descriptor.field(i);
    const bool set = field.is_repeated() ? reflection.FieldSize(message, &field) > 0
                                         : reflection.HasField(message, &field);
    if (!set) continue;
    if (absl::Status s = CheckField(message, field, place); !s.ok()) return s;
  }
  return absl::OkStatus();
}

absl::Status CheckField(const Message& message, const FieldDescriptor& field,
                        const FieldPlace* parent) {
  const Reflection& reflection = *message.GetReflection();
  const bool text = field.type() == FieldDescriptor::TYPE_STRING;
  const size_t max_bytes = text && IsPathField(field) ? kMaxPathBytes : kMaxNameBytes;
  const bool nested = field.cpp_type() == FieldDescriptor::CPPTYPE_MESSAGE;
  const int count = field.is_repeated() ? reflection.FieldSize(message, &field) : 1;
  for (int i = 0; i < count; ++i) {
    const FieldPlace place{parent, &field, field.is_repeated() ? i : -1};
    absl::Status s = absl::OkStatus();
    if (text) {
      std::string scratch;
      const std::string& value =
          field.is_repeated() ? reflection.GetRepeatedStringReference(message, &field, i, &scratch)
                              : reflection.GetStringReference(message, &field, &scratch);
      s = CheckText(value, "", max_bytes);
      if (!s.ok()) s = CheckText(value, Written(&place), max_bytes);  // again, naming the field
    }
    if (nested) {
      s = CheckMessage(field.is_repeated() ? reflection.GetRepeatedMessage(message, &field, i)
                                           : reflection.GetMessage(message, &field),
                       &place);
    }
    if (!s.ok()) return s;
  }
  return absl::OkStatus();
}

}  // namespace

absl::Status CheckText(absl::string_view text, absl::string_view field, size_t max_bytes) {
  if (text.size() > max_bytes) {
    return absl::InvalidArgumentError(absl::StrCat(
        field, ": is ", text.size(), " bytes long, more than the ", max_bytes, " allowed"));
  }
  for (size_t at = 0; at < text.size();) {
    const CodePoint c = DecodeUtf8(text, at);
    if (c.length == 0) {
      return absl::InvalidArgumentError(
          absl::StrFormat("%s: is not valid UTF-8 (byte 0x%02X at offset %d)", field,
                          static_cast<uint8_t>(text[at]), at));
    }
    if (IsControl(c.value)) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "%s: holds the control character U+%04X at offset %d; names and labels are one line "
          "of printable text",
          field, c.value, at));
    }
    at += c.length;
  }
  return absl::OkStatus();
}

absl::Status CheckMessageText(const Message& message, absl::string_view prefix) {
  absl::Status status = CheckMessage(message, nullptr);
  if (status.ok()) return status;
  return absl::Status(status.code(), absl::StrCat(prefix, status.message()));
}

std::string QuoteText(absl::string_view text, size_t max_bytes) {
  const bool cut = text.size() > max_bytes;
  return absl::StrCat("'", absl::CHexEscape(text.substr(0, max_bytes)), cut ? "...'" : "'");
}

}  // namespace fenestra
