#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace fenestra {

// Client text longer than this is cut in log lines [bytes].
inline constexpr size_t kLogSafeMaxBytes = 200;

// Client text (names, ids, peers, messages quoting them) made safe for one log line:
// control characters (C0, DEL, C1), Unicode line and paragraph separators and
// bidirectional overrides become escapes (\n, \x1b, \u2028), as do backslashes and double
// quotes; bytes that are not UTF-8 become \xNN. Only the first `max_bytes` bytes of `text`
// are shown, then "...(+N bytes)". The result never holds a line break, so a client cannot
// start a line of its own in the log.
std::string LogSafe(std::string_view text, size_t max_bytes = kLogSafeMaxBytes);

}  // namespace fenestra
