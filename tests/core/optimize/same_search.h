#pragma once

// Helpers of the search's tests: design variables, and whether two searches took the same
// steps to the same end.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "core/optimize/vns.h"

namespace fenestra {

// A design variable in [lower, upper] starting at `start`.
inline DesignVariable BoxVariable(std::string name, double lower, double upper, double start) {
  DesignVariable v;
  v.name = std::move(name);
  v.lower = lower;
  v.upper = upper;
  v.start = start;
  return v;
}

// Deterministic noise of unit variance for a design (like common random numbers: the same
// design and salt always get the same error).
inline double DesignNoise(const std::vector<double>& x, uint64_t salt = 0) {
  uint64_t h = 1469598103934665603ull ^ salt;
  for (double v : x) {
    uint64_t bits;
    std::memcpy(&bits, &v, sizeof bits);
    h = (h ^ bits) * 1099511628211ull;
    h ^= h >> 29;
  }
  const double u1 = ((h >> 11) + 0.5) * 0x1.0p-53;
  const double u2 = (((h * 6364136223846793005ull) >> 11) + 0.5) * 0x1.0p-53;
  return std::sqrt(-2 * std::log(u1)) * std::cos(2 * std::numbers::pi * u2);
}

// Every step (design, value, error, constraints, score, feasibility and what the search made
// of it) and the end (incumbent, counts, stopping rule) equal.
inline void ExpectSameSearch(const VnsResult& a, const VnsResult& b) {
  ASSERT_EQ(a.history.size(), b.history.size());
  for (size_t i = 0; i < a.history.size(); ++i) {
    SCOPED_TRACE(testing::Message() << "step " << i);
    const VnsRecord &x = a.history[i], &y = b.history[i];
    EXPECT_EQ(x.index, y.index);
    EXPECT_EQ(x.x, y.x);
    EXPECT_EQ(x.evaluation.value, y.evaluation.value);
    EXPECT_EQ(x.evaluation.standard_error, y.evaluation.standard_error);
    EXPECT_EQ(x.evaluation.constraints, y.evaluation.constraints);
    EXPECT_EQ(x.evaluation.partial, y.evaluation.partial);
    EXPECT_EQ(x.score, y.score);
    EXPECT_EQ(x.cached, y.cached);
    EXPECT_EQ(x.improved, y.improved);
    EXPECT_EQ(x.feasible, y.feasible);
    EXPECT_EQ(x.violation, y.violation);
    EXPECT_EQ(x.neighborhood, y.neighborhood);
  }
  EXPECT_EQ(a.best_x, b.best_x);
  EXPECT_EQ(a.best.value, b.best.value);
  EXPECT_EQ(a.best.standard_error, b.best.standard_error);
  EXPECT_EQ(a.best_score, b.best_score);
  EXPECT_EQ(a.best_index, b.best_index);
  EXPECT_EQ(a.evaluations, b.evaluations);
  EXPECT_EQ(a.cache_hits, b.cache_hits);
  EXPECT_EQ(a.improvements, b.improvements);
  EXPECT_EQ(a.stop_reason, b.stop_reason);
}

}  // namespace fenestra
