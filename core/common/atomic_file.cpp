#include "core/common/atomic_file.h"

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "absl/strings/str_cat.h"

namespace fenestra {

absl::Status WriteFileAtomically(const std::string& path,
                                 const std::function<absl::Status(std::ostream&)>& write,
                                 bool binary) {
  const std::string tmp = absl::StrCat(path, ".tmp.", getpid());
  absl::Status status;
  {
    std::ofstream out(tmp, binary ? std::ios::binary | std::ios::trunc : std::ios::trunc);
    if (!out) return absl::NotFoundError(absl::StrCat(path, ": cannot open for writing"));
    status = write(out);
    out.flush();
    if (status.ok() && !out) status = absl::DataLossError(absl::StrCat(path, ": write failed"));
  }
  std::error_code ec;
  if (!status.ok()) {
    std::filesystem::remove(tmp, ec);
    return status;
  }
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::filesystem::remove(tmp, ec);
    return absl::InternalError(
        absl::StrCat(path, ": cannot rename temporary file: ", ec.message()));
  }
  return absl::OkStatus();
}

}  // namespace fenestra
