// Store: the users.
#include "absl/strings/str_cat.h"
#include "core/common/status_macros.h"
#include "server/store/store.h"
#include "server/store/store_internal.h"

namespace fenestra {

namespace {

using store_internal::Blob;

}  // namespace

// ---- Users

absl::Status Store::InsertUser(const UserRecord& user) {
  const absl::Status status = Transact([&](SqlSession& s) {
    return s
        .Run(
            "INSERT INTO users (name, token_sha256, admin, created_unix_ms, revoked_unix_ms) "
            "VALUES (?, ?, ?, ?, ?)",
            {user.name, Blob(user.token_sha256), int64_t{user.admin}, user.created_unix_ms,
             user.revoked_unix_ms})
        .status();
  });
  if (status.code() == absl::StatusCode::kAlreadyExists) {
    return absl::AlreadyExistsError(absl::StrCat("user '", user.name, "' exists"));
  }
  return status;
}

absl::StatusOr<std::vector<UserRecord>> Store::LoadUsers() {
  std::vector<UserRecord> users;
  FENESTRA_RETURN_IF_ERROR(Transact(
      [&](SqlSession& s) -> absl::Status {
        FENESTRA_ASSIGN_OR_RETURN(
            rows, s.Run("SELECT name, token_sha256, admin, created_unix_ms, revoked_unix_ms FROM "
                        "users ORDER BY number"));
        users.clear();
        for (const SqlRow& r : rows.rows) {
          users.push_back(UserRecord{r.Bytes(0), r.Bytes(1), r.Int(2) != 0, r.Int(3), r.Int(4)});
        }
        return absl::OkStatus();
      },
      /*durable=*/false, /*write=*/false));
  return users;
}

absl::Status Store::RevokeUser(const std::string& name, int64_t unix_ms) {
  return Transact([&](SqlSession& s) -> absl::Status {
    FENESTRA_ASSIGN_OR_RETURN(
        updated, s.Run("UPDATE users SET revoked_unix_ms = CASE WHEN revoked_unix_ms = 0 THEN ? "
                       "ELSE revoked_unix_ms END WHERE name = ?",
                       {unix_ms, name}));
    if (updated.changed == 0) return absl::NotFoundError(absl::StrCat("no user '", name, "'"));
    return absl::OkStatus();
  });
}

}  // namespace fenestra
