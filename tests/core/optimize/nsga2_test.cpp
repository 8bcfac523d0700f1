// NSGA-II (core/optimize/nsga2.h) on ZDT1 (Zitzler, Deb & Thiele 2000), whose Pareto front is
// known: f2 = 1 - sqrt(f1), f1 in [0, 1], where x2..xn are 0; its hypervolume below (1, 1) is
// the integral of sqrt(f1) over [0, 1], 2/3. Seeds are fixed.
#include "core/optimize/nsga2.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

namespace fenestra {
namespace {

std::vector<double> Zdt1(const std::vector<double>& x) {
  double sum = 0;
  for (size_t i = 1; i < x.size(); ++i) sum += x[i];
  const double g = 1 + 9 * sum / static_cast<double>(x.size() - 1);
  return {x[0], g * (1 - std::sqrt(x[0] / g))};
}

void Step(Nsga2& search) {
  std::vector<std::vector<double>> objectives;
  for (const std::vector<double>& x : search.Ask()) objectives.push_back(Zdt1(x));
  ASSERT_TRUE(search.Tell(objectives).ok());
}

Nsga2 Zdt1Search(int variables, int population, uint64_t seed) {
  Nsga2Options options;
  options.population = population;
  options.seed = seed;
  absl::StatusOr<Nsga2> search = Nsga2::Make(std::vector<double>(variables, 0.0),
                                             std::vector<double>(variables, 1.0), 2, options);
  EXPECT_TRUE(search.ok()) << search.status();
  return *std::move(search);
}

TEST(Nsga2Test, RecoversTheFrontOfZdt1) {
  Nsga2 search = Zdt1Search(10, 200, 7);
  Step(search);  // the first population
  for (int g = 0; g < 250; ++g) Step(search);
  EXPECT_EQ(search.Generation(), 250);
  const std::vector<Nsga2Member> front = search.Front();
  const double volume = Hypervolume2d(front, 1.0, 1.0);
  std::printf("ZDT1: %zu members on the first front, hypervolume %.5f (true front %.5f)\n",
              front.size(), volume, 2.0 / 3.0);
  EXPECT_GE(front.size(), 100u);
  EXPECT_NEAR(volume, 2.0 / 3.0, 0.01 * 2.0 / 3.0);
  // Nine in ten members lie within 0.01 of the true front, every one within 0.05 (an end of
  // the front may hold a member above it that none of the rest dominates), and they spread
  // over it
  size_t near = 0;
  for (const Nsga2Member& m : front) {
    const double off = std::abs(m.objectives[1] - (1 - std::sqrt(m.objectives[0])));
    EXPECT_LT(off, 0.05);
    near += off <= 0.01 ? 1 : 0;
  }
  EXPECT_GE(near, 9 * front.size() / 10);
  EXPECT_LT(front.front().objectives[0], 0.01);
  EXPECT_GT(front.back().objectives[0], 0.99);
}

// A search saved mid-way and restored from its state goes on as the one never stopped: the
// same designs asked, the same front.
TEST(Nsga2Test, ARestoredSearchEndsAsTheUninterruptedOne) {
  Nsga2 straight = Zdt1Search(5, 20, 3);
  for (int g = 0; g < 31; ++g) Step(straight);
  Nsga2 first_half = Zdt1Search(5, 20, 3);
  for (int g = 0; g < 16; ++g) Step(first_half);
  const Nsga2State saved = first_half.Save();
  absl::StatusOr<Nsga2> resumed = Nsga2::Restore(saved);
  ASSERT_TRUE(resumed.ok()) << resumed.status();
  EXPECT_EQ(resumed->Ask(), first_half.Ask());
  for (int g = 16; g < 31; ++g) Step(*resumed);
  EXPECT_EQ(resumed->Generation(), straight.Generation());
  const std::vector<Nsga2Member> a = straight.Front(), b = resumed->Front();
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].x, b[i].x);
    EXPECT_EQ(a[i].objectives, b[i].objectives);
  }
}

// A design is dominated only when it is worse beyond the combined errors.
TEST(Nsga2Test, DominanceNeedsADifferenceBeyondTheErrors) {
  const Nsga2Member a{{}, {1.0, 1.0}, {0.1, 0.1}, 0, 0};
  const Nsga2Member b{{}, {1.05, 1.05}, {0.1, 0.1}, 0, 0};
  const Nsga2Member c{{}, {1.5, 1.02}, {0.1, 0.1}, 0, 0};
  EXPECT_TRUE(Dominates(a, b, 0));
  EXPECT_FALSE(Dominates(a, b, 2));  // 0.05 apart, 0.28 is 2 combined errors
  EXPECT_TRUE(Dominates(a, c, 2));   // better by 0.5 in one, within the errors in the other
  EXPECT_FALSE(Dominates(c, a, 2));
  std::vector<Nsga2Member> members = {a, b, c};
  RankAndCrowd(members, 2);
  EXPECT_EQ(members[0].rank, 0);
  EXPECT_EQ(members[1].rank, 0);  // not dominated beyond its errors
  EXPECT_EQ(members[2].rank, 1);
}

TEST(Nsga2Test, HypervolumeOfAStaircase) {
  EXPECT_DOUBLE_EQ(Hypervolume2d({{{}, {0.5, 0.5}, {}, 0, 0}}, 1, 1), 0.25);
  EXPECT_DOUBLE_EQ(Hypervolume2d({{{}, {0.75, 0.25}, {}, 0, 0},
                                  {{}, {0.25, 0.75}, {}, 0, 0},
                                  {{}, {0.8, 0.8}, {}, 0, 0},
                                  {{}, {1.5, 0.0}, {}, 0, 0}},
                                 1, 1),
                   0.75 * 0.25 + 0.25 * 0.5);
}

TEST(Nsga2Test, BadSettingsAndTellsAreRefused) {
  Nsga2Options odd;
  odd.population = 21;
  EXPECT_FALSE(Nsga2::Make({0}, {1}, 2, odd).ok());
  EXPECT_FALSE(Nsga2::Make({0}, {1}, 1, {}).ok());
  EXPECT_FALSE(Nsga2::Make({1}, {0}, 2, {}).ok());
  EXPECT_FALSE(Nsga2::Make({0, 0}, {1}, 2, {}).ok());
  EXPECT_FALSE(Nsga2::Make({0}, {INFINITY}, 2, {}).ok());
  absl::StatusOr<Nsga2> search = Nsga2::Make({0}, {1}, 2, {});
  ASSERT_TRUE(search.ok());
  EXPECT_FALSE(search->Tell({{1, 2}}).ok());  // one for 40 designs
  std::vector<std::vector<double>> bad(search->Ask().size(), {1.0, NAN});
  EXPECT_FALSE(search->Tell(bad).ok());
  EXPECT_EQ(search->Generation(), 0);
}

}  // namespace
}  // namespace fenestra
