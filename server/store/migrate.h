#pragma once

#include <functional>
#include <string>

#include "absl/status/status.h"

namespace fenestra {

// `fenestrad migrate`: copies what the data directory `from_dir` holds (its SQLite store:
// users, jobs with their events and checkpoints, sites, quarantine; its weather files and
// outdoor matrix files) into the PostgreSQL store `to_url`, created or upgraded first.
// The data directory is locked meanwhile, so no fenestrad may run on it, and is left as
// it was. The target must be empty unless `overwrite` (FailedPrecondition otherwise).
// Corrupt matrix files are left out (they are traced again when needed). `progress` hears
// what was copied.
absl::Status MigrateDataDir(const std::string& from_dir, const std::string& to_url, bool overwrite,
                            const std::function<void(const std::string&)>& progress);

}  // namespace fenestra
