#include "server/upload_quota.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace fenestra {
namespace {

using ::testing::HasSubstr;

TEST(UploadQuotaTest, EachUserHoldsUpToTheLimit) {
  UploadQuota quota(1000);
  EXPECT_TRUE(quota.Reserve("ann", 600).ok());
  EXPECT_TRUE(quota.Reserve("bob", 900).ok());
  const absl::Status over = quota.Reserve("ann", 401);
  EXPECT_EQ(over.code(), absl::StatusCode::kResourceExhausted);
  EXPECT_THAT(over.message(), HasSubstr("limits.max_upload_bytes_per_user (1000) reached"));
  EXPECT_THAT(over.message(), HasSubstr("hold 600 bytes"));
  EXPECT_TRUE(quota.Reserve("ann", 400).ok());
  EXPECT_EQ(quota.Held("ann"), 1000);
  EXPECT_TRUE(quota.Reserve("ann", 0).ok());  // a request without upload always passes
  quota.Release("ann", 600);
  EXPECT_EQ(quota.Held("ann"), 400);
  // What a restart finds stored is counted whatever the limit
  EXPECT_TRUE(quota.Reserve("bob", 500, /*force=*/true).ok());
  EXPECT_EQ(quota.Held("bob"), 1400);
  quota.Release("bob", 1400);
  EXPECT_EQ(quota.Held("bob"), 0);
}

}  // namespace
}  // namespace fenestra
