#pragma once

#include <functional>
#include <ostream>
#include <string>

#include "absl/status/status.h"

namespace fenestra {

// Writes a file through `write` into a temporary sibling, then renames it onto `path`.
// If `write` fails or the stream goes bad, the temporary is removed and `path` is untouched.
absl::Status WriteFileAtomically(const std::string& path,
                                 const std::function<absl::Status(std::ostream&)>& write,
                                 bool binary = false);

}  // namespace fenestra
