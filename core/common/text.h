// Checks on the free text a client sends (names, labels, paths), and quoting of untrusted
// text in messages, so that no client string can break a log line or a terminal.
#pragma once

#include <google/protobuf/message.h>

#include <cstddef>
#include <string>

#include "absl/status/status.h"
#include "absl/strings/string_view.h"

namespace fenestra {

// Longest name or label [bytes]: scene, material, surface, sensor, job and site names.
inline constexpr size_t kMaxNameBytes = 256;
// Longest file path [bytes] (Linux's PATH_MAX).
inline constexpr size_t kMaxPathBytes = 4096;

// OkStatus when `text` is valid UTF-8 of at most `max_bytes` bytes without control
// characters (C0, DEL, C1, line and paragraph separators, bidirectional overrides).
// Otherwise InvalidArgument "<field>: <reason>"; the reason never repeats the text.
absl::Status CheckText(absl::string_view text, absl::string_view field,
                       size_t max_bytes = kMaxNameBytes);

// CheckText on every string field of `message`, nested messages, repeated fields and map
// keys included; fields named `path` or `*_file` may hold kMaxPathBytes. Fields are named
// `prefix` + their path, e.g. "job scene.sensors[3].name".
absl::Status CheckMessageText(const google::protobuf::Message& message, absl::string_view prefix);

// `text` in single quotes for a message: at most `max_bytes` of it, bytes outside printable
// ASCII as \xNN escapes, "..." when cut.
std::string QuoteText(absl::string_view text, size_t max_bytes = 64);

}  // namespace fenestra
