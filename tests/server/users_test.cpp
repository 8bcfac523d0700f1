#include "server/users.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <set>

#include "server/checksum.h"

namespace fenestra {
namespace {

using ::testing::HasSubstr;

std::unique_ptr<Store> FreshStore(const std::string& name) {
  const std::string dir = testing::TempDir() + "/users_test_" + name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  auto store = OpenStoreUrl("sqlite:" + dir);
  EXPECT_TRUE(store.ok()) << store.status();
  return *std::move(store);
}

TEST(UsersTest, TokensAre256RandomBitsInHex) {
  std::set<std::string> seen;
  for (int i = 0; i < 100; ++i) {
    absl::StatusOr<std::string> token = NewToken();
    ASSERT_TRUE(token.ok()) << token.status();
    ASSERT_EQ(token->size(), 64u);
    EXPECT_EQ(token->find_first_not_of("0123456789abcdef"), std::string::npos) << *token;
    seen.insert(*token);
  }
  EXPECT_EQ(seen.size(), 100u);
}

TEST(UsersTest, UserNamesAreCheckedAndLocalIsReserved) {
  EXPECT_TRUE(CheckUserName("ann").ok());
  EXPECT_TRUE(CheckUserName("ann.lee_2-b").ok());
  EXPECT_TRUE(CheckUserName(std::string(64, 'a')).ok());
  for (const std::string& bad :
       {std::string(), std::string(65, 'a'), std::string("-ann"), std::string("ann lee"),
        std::string("ann\nlee"), std::string("ann\"")}) {
    EXPECT_EQ(CheckUserName(bad).code(), absl::StatusCode::kInvalidArgument) << bad;
  }
  EXPECT_THAT(CheckUserName("local").message(), HasSubstr("reserved"));
}

TEST(UsersTest, OnlyTheTokensHashIsStoredAndNamesAreUnique) {
  std::unique_ptr<Store> store = FreshStore("stored");
  absl::StatusOr<std::string> token = AddUser(*store, "ann", /*admin=*/false);
  ASSERT_TRUE(token.ok()) << token.status();
  ASSERT_TRUE(AddUser(*store, "root", /*admin=*/true).ok());
  EXPECT_EQ(AddUser(*store, "ann", true).status().code(), absl::StatusCode::kAlreadyExists);
  absl::StatusOr<std::vector<UserRecord>> users = store->LoadUsers();
  ASSERT_TRUE(users.ok());
  ASSERT_EQ(users->size(), 2u);
  EXPECT_EQ((*users)[0].name, "ann");
  EXPECT_FALSE((*users)[0].admin);
  EXPECT_TRUE((*users)[1].admin);
  EXPECT_EQ((*users)[0].token_sha256, Sha256(*token));
  EXPECT_GT((*users)[0].created_unix_ms, 0);
  EXPECT_EQ((*users)[0].revoked_unix_ms, 0);
}

TEST(UsersTest, AuthenticatorKnowsTokensAndNothingElse) {
  std::unique_ptr<Store> store = FreshStore("auth");
  const std::string ann = *AddUser(*store, "ann", false);
  const std::string root = *AddUser(*store, "root", true);
  const Authenticator auth("token", *store);

  absl::StatusOr<Caller> caller = auth.Authenticate("Bearer " + ann);
  ASSERT_TRUE(caller.ok()) << caller.status();
  EXPECT_EQ(caller->name, "ann");
  EXPECT_FALSE(caller->admin);
  caller = auth.Authenticate("bearer " + root);  // the scheme is case-insensitive
  ASSERT_TRUE(caller.ok()) << caller.status();
  EXPECT_EQ(caller->name, "root");
  EXPECT_TRUE(caller->admin);

  // No token, another scheme: the caller is told to send one
  for (const std::optional<std::string_view>& none :
       {std::optional<std::string_view>(), std::optional<std::string_view>(ann),
        std::optional<std::string_view>("Basic YW5uOnB3")}) {
    const absl::Status status = auth.Authenticate(none).status();
    EXPECT_EQ(status.code(), absl::StatusCode::kUnauthenticated);
    EXPECT_THAT(status.message(), HasSubstr("authorization: Bearer"));
  }
  // A wrong, unknown or revoked token: one message for all
  std::string wrong = ann;
  wrong[10] = wrong[10] == 'a' ? 'b' : 'a';
  const std::string invalid = std::string(auth.Authenticate("Bearer " + wrong).status().message());
  EXPECT_THAT(invalid, HasSubstr("not valid"));
  EXPECT_EQ(auth.Authenticate("Bearer " + *NewToken()).status().message(), invalid);
  EXPECT_EQ(auth.Authenticate("Bearer ").status().message(), invalid);
  ASSERT_TRUE(store->RevokeUser("ann", 1234).ok());
  EXPECT_EQ(auth.Authenticate("Bearer " + ann).status().code(), absl::StatusCode::kUnauthenticated);
  EXPECT_EQ(auth.Authenticate("Bearer " + ann).status().message(), invalid);
  EXPECT_TRUE(auth.Authenticate("Bearer " + root).ok());
  // Revoking again keeps the first time; an unknown user is NotFound
  ASSERT_TRUE(store->RevokeUser("ann", 5678).ok());
  EXPECT_EQ((*store->LoadUsers())[0].revoked_unix_ms, 1234);
  EXPECT_EQ(store->RevokeUser("bob", 1).code(), absl::StatusCode::kNotFound);
}

TEST(UsersTest, AuthNoneMakesEveryCallerTheLocalAdministrator) {
  std::unique_ptr<Store> store = FreshStore("none");
  absl::StatusOr<Caller> caller = Authenticator("none", *store).Authenticate(std::nullopt);
  ASSERT_TRUE(caller.ok());
  EXPECT_EQ(caller->name, kLocalUser);
  EXPECT_TRUE(caller->admin);
}

TEST(UsersTest, CallersSeeOwnersOnlyAsAdministrators) {
  const Caller ann{"ann", false}, root{"root", true};
  EXPECT_TRUE(ann.Owns("ann"));
  EXPECT_FALSE(ann.Owns("bob"));
  EXPECT_TRUE(root.Owns("bob"));
  v1::JobInfo info;
  info.set_owner("ann");
  EXPECT_EQ(ForCaller(info, ann).owner(), "");
  EXPECT_EQ(ForCaller(info, root).owner(), "ann");
}

}  // namespace
}  // namespace fenestra
