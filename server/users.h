#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "server/store/store.h"

namespace fenestra {

// Who calls an RPC, as the job and site managers see it.
struct Caller {
  std::string name;
  bool admin = false;
  // True when the caller may see and act on what `owner` made: its own, or anything for
  // an administrator.
  bool Owns(const std::string& owner) const { return admin || owner == name; }
};

// `info` (a JobInfo or SiteInfo) as `caller` may see it: the owner, and the replica that
// runs a job, only for administrators.
template <typename Info>
Info ForCaller(Info info, const Caller& caller) {
  if (caller.admin) return info;
  info.clear_owner();
  if constexpr (requires { info.clear_replica(); }) info.clear_replica();
  return info;
}

// The one caller of `auth none` (an administrator); also the owner of jobs and sites
// stored before owners were recorded. Reserved: no token user may take the name.
inline constexpr char kLocalUser[] = "local";

// Checks a user name: 1 to 64 characters of [A-Za-z0-9._-], the first a letter or digit,
// and not the reserved kLocalUser. InvalidArgument saying why otherwise.
absl::Status CheckUserName(const std::string& name);

// A new token: 32 bytes (256 bits) from the kernel's CSPRNG (getrandom), as 64 lowercase
// hex digits.
absl::StatusOr<std::string> NewToken();

// Adds a user with a new token and returns the token, which is stored only as its
// SHA-256. AlreadyExists when the name is taken (revoked users included).
absl::StatusOr<std::string> AddUser(UserStore& users, const std::string& name, bool admin);

// Tells callers apart by the "authorization: Bearer <token>" metadata of their calls.
// Users are read from the store at every call, so `fenestrad user add` and `user revoke`
// take effect on a running daemon at once.
class Authenticator {
 public:
  // `mode`: DaemonConfig.auth, "token" or "none".
  Authenticator(std::string mode, UserStore& users) : mode_(std::move(mode)), users_(users) {}

  // The caller whose token `authorization` carries (the metadata's value, if sent); with
  // auth none, the local user. Unauthenticated without a token, and with one message for
  // every token that is not a user's (unknown, wrong or revoked); the token's hash is
  // compared with every user's in constant time.
  absl::StatusOr<Caller> Authenticate(std::optional<std::string_view> authorization) const;

 private:
  const std::string mode_;
  UserStore& users_;
};

}  // namespace fenestra
