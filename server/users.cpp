#include "server/users.h"

#include <openssl/crypto.h>
#include <sys/random.h>

#include <cerrno>
#include <chrono>
#include <cstring>

#include "absl/strings/ascii.h"
#include "absl/strings/escaping.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/strip.h"
#include "server/checksum.h"

namespace fenestra {
namespace {

constexpr size_t kTokenBytes = 32;
constexpr size_t kMaxUserNameLength = 64;

}  // namespace

absl::Status CheckUserName(const std::string& name) {
  const auto allowed = [](char c) {
    return absl::ascii_isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '_' || c == '-';
  };
  if (name.empty() || name.size() > kMaxUserNameLength ||
      !absl::ascii_isalnum(static_cast<unsigned char>(name[0])) ||
      !std::all_of(name.begin(), name.end(), allowed)) {
    return absl::InvalidArgumentError(
        absl::StrCat("a user name is 1 to ", kMaxUserNameLength,
                     " letters, digits, '.', '_' or '-', starting with a letter or digit"));
  }
  if (name == kLocalUser) {
    return absl::InvalidArgumentError(
        absl::StrCat("the user name '", kLocalUser, "' is reserved for auth none"));
  }
  return absl::OkStatus();
}

absl::StatusOr<std::string> NewToken() {
  unsigned char bytes[kTokenBytes];
  size_t filled = 0;
  while (filled < kTokenBytes) {
    const ssize_t n = getrandom(bytes + filled, kTokenBytes - filled, 0);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      return absl::InternalError(
          absl::StrCat("cannot read random bytes (getrandom): ", std::strerror(errno)));
    }
    filled += static_cast<size_t>(n);
  }
  std::string token =
      absl::BytesToHexString(absl::string_view(reinterpret_cast<char*>(bytes), kTokenBytes));
  OPENSSL_cleanse(bytes, kTokenBytes);
  return token;
}

absl::StatusOr<std::string> AddUser(UserStore& users, const std::string& name, bool admin) {
  if (absl::Status s = CheckUserName(name); !s.ok()) return s;
  absl::StatusOr<std::string> token = NewToken();
  if (!token.ok()) return token.status();
  UserRecord user;
  user.name = name;
  user.token_sha256 = Sha256(*token);
  user.admin = admin;
  user.created_unix_ms = std::chrono::duration_cast<std::chrono::milliseconds>(
                             std::chrono::system_clock::now().time_since_epoch())
                             .count();
  if (absl::Status s = users.InsertUser(user); !s.ok()) return s;
  return token;
}

absl::StatusOr<Caller> Authenticator::Authenticate(
    std::optional<std::string_view> authorization) const {
  if (mode_ == "none") return Caller{kLocalUser, /*admin=*/true};
  const std::string_view value = authorization.value_or("");
  absl::string_view token(value.data(), value.size());
  if (token.size() < 7 || !absl::EqualsIgnoreCase(token.substr(0, 7), "bearer ")) {
    return absl::UnauthenticatedError(
        "this server needs a token: send the metadata 'authorization: Bearer <token>' (an "
        "administrator makes one with `fenestrad user add`)");
  }
  token = absl::StripLeadingAsciiWhitespace(token.substr(7));
  const std::string hash = Sha256(std::string_view(token.data(), token.size()));
  absl::StatusOr<std::vector<UserRecord>> users = users_.LoadUsers();
  if (!users.ok()) return users.status();
  // Every user's hash is compared, to the end, whatever matched before
  const UserRecord* match = nullptr;
  for (const UserRecord& user : *users) {
    const bool equal = user.token_sha256.size() == hash.size() &&
                       CRYPTO_memcmp(user.token_sha256.data(), hash.data(), hash.size()) == 0;
    if (equal && user.revoked_unix_ms == 0) match = &user;
  }
  if (match == nullptr) {
    return absl::UnauthenticatedError("the token is not valid (unknown, wrong or revoked)");
  }
  return Caller{match->name, match->admin};
}

}  // namespace fenestra
