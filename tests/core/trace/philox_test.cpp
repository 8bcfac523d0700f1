#include "core/trace/philox.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>

namespace fenestra {
namespace {

void ExpectBlock(Philox4x32 counter, uint32_t key0, uint32_t key1, Philox4x32 expected) {
  const Philox4x32 got = Philox4x32_10(counter, key0, key1);
  for (int i = 0; i < 4; ++i) EXPECT_EQ(got.v[i], expected.v[i]) << "word " << i;
}

// Random123's known-answer vectors for Philox4x32-10.
TEST(PhiloxTest, MatchesRandom123KnownAnswers) {
  ExpectBlock({{0, 0, 0, 0}}, 0, 0, {{0x6627e8d5, 0xe169c58d, 0xbc57ac4c, 0x9b00dbd8}});
  ExpectBlock({{0xffffffff, 0xffffffff, 0xffffffff, 0xffffffff}}, 0xffffffff, 0xffffffff,
              {{0x408f276d, 0x41c83b0e, 0xa20bc7c6, 0x6d5451fd}});
  ExpectBlock({{0x243f6a88, 0x85a308d3, 0x13198a2e, 0x03707344}}, 0xa4093822, 0x299f31d0,
              {{0xd16cfe09, 0x94fdcceb, 0x5001e420, 0x24126ea1}});
}

TEST(PhiloxTest, UniformFloatStaysInUnitInterval) {
  EXPECT_EQ(UniformFloat(0), 0.0f);
  EXPECT_LT(UniformFloat(0xffffffffu), 1.0f);
  EXPECT_GT(UniformFloat(0xffffffffu), 0.9999f);
}

TEST(PhiloxTest, StreamsArePureFunctionsOfTheirInputs) {
  const PathRandom a(42, 3, 1234567890123ull), b(42, 3, 1234567890123ull);
  const Uniform4 x = a.Draw(7, 0), y = b.Draw(7, 0);
  for (int i = 0; i < 4; ++i) EXPECT_EQ(x.u[i], y.u[i]);
  // Any change of seed, stream, path, vertex or purpose changes the numbers
  const Uniform4 others[] = {PathRandom(43, 3, 1234567890123ull).Draw(7, 0),
                             PathRandom(42, 4, 1234567890123ull).Draw(7, 0),
                             PathRandom(42, 3, 1234567890124ull).Draw(7, 0),
                             PathRandom(42, 3, 1234567890123ull + (1ull << 32)).Draw(7, 0),
                             a.Draw(8, 0),
                             a.Draw(7, 1)};
  for (const Uniform4& o : others) EXPECT_NE(o.u[0], x.u[0]);
}

TEST(PhiloxTest, UniformsHaveTheRightMoments) {
  // Mean 1/2 and variance 1/12 over 4 * 10^5 draws, within 5 standard errors
  double sum = 0, sum_squares = 0;
  const int kBlocks = 100000;
  for (int p = 0; p < kBlocks; ++p) {
    const Uniform4 u = PathRandom(7, 0, p).Draw(0, 0);
    for (float x : u.u) {
      sum += x;
      sum_squares += double(x) * x;
    }
  }
  const double n = 4.0 * kBlocks;
  EXPECT_NEAR(sum / n, 0.5, 5 * std::sqrt(1.0 / 12 / n));
  EXPECT_NEAR(sum_squares / n - (sum / n) * (sum / n), 1.0 / 12, 5 * std::sqrt(1.0 / 180 / n));
}

}  // namespace
}  // namespace fenestra
