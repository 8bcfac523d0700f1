#include "server/heavy_requests.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <optional>

namespace fenestra {
namespace {

TEST(HeavyRequestsTest, BeyondTheLimitHeavyRequestsAreRefusedLightOnesNever) {
  HeavyRequests heavy(2);
  std::optional<absl::StatusOr<HeavyRequests::Pass>> first(heavy.Enter(kHeavyRequestBytes));
  absl::StatusOr<HeavyRequests::Pass> second = heavy.Enter(60 << 20);
  ASSERT_TRUE(first->ok());
  ASSERT_TRUE(second.ok());
  absl::StatusOr<HeavyRequests::Pass> third = heavy.Enter(kHeavyRequestBytes);
  EXPECT_EQ(third.status().code(), absl::StatusCode::kResourceExhausted);
  EXPECT_THAT(third.status().message(), testing::HasSubstr("max_concurrent_heavy_requests"));
  EXPECT_TRUE(heavy.Enter(kHeavyRequestBytes - 1).ok());
  // A pass given back frees its slot
  first.reset();
  EXPECT_TRUE(heavy.Enter(kHeavyRequestBytes).ok());
}

}  // namespace
}  // namespace fenestra
