#include "server/store/database.h"

#include "absl/strings/str_cat.h"
#include "absl/strings/str_replace.h"

namespace fenestra {

int64_t SqlRow::Int(size_t column) const {
  if (const int64_t* value = std::get_if<int64_t>(&cells_[column])) return *value;
  if (const std::string* text = std::get_if<std::string>(&cells_[column])) {
    int64_t value = 0;
    return absl::SimpleAtoi(*text, &value) ? value : 0;
  }
  return 0;
}

std::string SqlRow::Bytes(size_t column) const {
  if (const std::string* bytes = std::get_if<std::string>(&cells_[column])) return *bytes;
  if (const int64_t* value = std::get_if<int64_t>(&cells_[column])) return absl::StrCat(*value);
  return "";
}

std::string SqlRow::TakeBytes(size_t column) {
  if (std::string* bytes = std::get_if<std::string>(&cells_[column])) return std::move(*bytes);
  return Bytes(column);
}

std::string Database::Sql(std::string_view sql) const {
  if (dialect() == Dialect::kSqlite) {
    return absl::StrReplaceAll(
        absl::string_view(sql.data(), sql.size()),
        {{"{now}", "CAST((julianday('now') - 2440587.5) * 86400000.0 AS INTEGER)"},
         {"{blob}", "BLOB"},
         {"{int}", "INTEGER"},
         {"{serial}", "INTEGER PRIMARY KEY AUTOINCREMENT"},
         {"{claim_lock}", ""},
         {"{for_update}", ""}});
  }
  return absl::StrReplaceAll(
      absl::string_view(sql.data(), sql.size()),
      {{"{now}", "CAST(EXTRACT(EPOCH FROM clock_timestamp()) * 1000 AS BIGINT)"},
       {"{blob}", "BYTEA"},
       {"{int}", "BIGINT"},
       {"{serial}", "BIGSERIAL PRIMARY KEY"},
       {"{claim_lock}", " FOR UPDATE OF c SKIP LOCKED"},
       {"{for_update}", " FOR UPDATE"}});
}

uint64_t Database::ChangeCount() const {
  std::lock_guard lock(change_mutex_);
  return changes_;
}

bool Database::WaitForChange(uint64_t seen, std::chrono::milliseconds timeout) const {
  std::unique_lock lock(change_mutex_);
  return change_cv_.wait_for(lock, timeout, [&] { return changes_ > seen; });
}

void Database::Changed() {
  {
    std::lock_guard lock(change_mutex_);
    ++changes_;
  }
  change_cv_.notify_all();
}

}  // namespace fenestra
