#include "server/store/migrate.h"

#include <filesystem>
#include <fstream>
#include <sstream>

#include "absl/strings/str_cat.h"
#include "core/common/status_macros.h"
#include "server/data_dir.h"
#include "server/outdoor_cache.h"
#include "server/store/postgres_database.h"
#include "server/store/sqlite_database.h"
#include "server/store/store.h"

namespace fenestra {

absl::Status MigrateDataDir(const std::string& from_dir, const std::string& to_url, bool overwrite,
                            const std::function<void(const std::string&)>& progress) {
  if (!IsPostgresUrl(to_url)) {
    return absl::InvalidArgumentError(
        absl::StrCat("--to '", RedactPostgresUrl(to_url),
                     "': give a PostgreSQL URL, postgresql://user@host:port/database"));
  }
  if (!std::filesystem::exists(std::filesystem::path(from_dir) / "fenestra.db")) {
    return absl::NotFoundError(
        absl::StrCat("no ", from_dir, "/fenestra.db: --from names a fenestrad data directory"));
  }
  // The data directory, locked: no daemon may change it while it is copied
  FENESTRA_ASSIGN_OR_RETURN(dir, DataDir::Open(from_dir, INT64_MAX));
  UploadStore weather(*dir, dir->weather_dir(), "epw");
  FENESTRA_ASSIGN_OR_RETURN(
      source_db, SqliteDatabase::Open(dir->db_path().string(), SqliteDatabase::Sharing::kShared));
  FENESTRA_ASSIGN_OR_RETURN(source, Store::Open(std::move(source_db), &weather));
  FENESTRA_ASSIGN_OR_RETURN(target_db, PostgresDatabase::Open(to_url, 1));
  FENESTRA_ASSIGN_OR_RETURN(target, Store::Open(std::move(target_db)));
  FENESTRA_RETURN_IF_ERROR(source->CopyTo(*target, overwrite, progress));

  // The matrix files, as the bytes they hold
  int copied = 0, left_out = 0;
  std::error_code error;
  for (const auto& file : std::filesystem::directory_iterator(dir->outdoor_dir(), error)) {
    if (file.path().extension() != ".omx") continue;
    std::ifstream in(file.path(), std::ios::binary);
    std::stringstream bytes;
    bytes << in.rdbuf();
    absl::StatusOr<OutdoorMatrix> matrix = DecodeOutdoorMatrix(bytes.str());
    if (!in || !matrix.ok()) {
      ++left_out;
      if (progress) {
        progress(absl::StrCat("left out ", file.path().string(), ": ",
                              in ? matrix.status().message() : "cannot be read"));
      }
      continue;
    }
    FENESTRA_RETURN_IF_ERROR(target->PutMatrix(matrix->key, bytes.str()));
    ++copied;
  }
  if (progress) {
    progress(absl::StrCat("outdoor matrices: ", copied, " files",
                          left_out ? absl::StrCat(" (", left_out, " corrupt, left out)") : ""));
  }
  return absl::OkStatus();
}

}  // namespace fenestra
