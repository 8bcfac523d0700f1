// The Owen-scrambled Sobol points (sobol.h) and the quasi-random draws of a path (philox.h):
// the direction numbers against Joe & Kuo's recurrence, the nets the points form scrambled
// or not, the scramble's uniformity, and a smooth integral whose error the points cut.
#include "core/trace/sobol.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "core/trace/philox.h"

namespace fenestra {
namespace {

// Joe & Kuo's parameters of dimensions 2 to 16 (their d): degree s, coefficients a, m_1..m_s.
struct Polynomial {
  int s, a;
  std::vector<uint32_t> m;
};
const Polynomial kJoeKuo[] = {{1, 0, {1}},
                              {2, 1, {1, 3}},
                              {3, 1, {1, 3, 1}},
                              {3, 2, {1, 1, 1}},
                              {4, 1, {1, 1, 3, 3}},
                              {4, 4, {1, 3, 5, 13}},
                              {5, 2, {1, 1, 5, 5, 17}},
                              {5, 4, {1, 1, 5, 5, 5}},
                              {5, 7, {1, 1, 7, 11, 19}},
                              {5, 11, {1, 1, 5, 1, 1}},
                              {5, 13, {1, 1, 1, 3, 11}},
                              {5, 14, {1, 3, 5, 5, 31}},
                              {6, 1, {1, 3, 3, 9, 7, 49}},
                              {6, 13, {1, 1, 1, 15, 21, 21}},
                              {6, 16, {1, 3, 1, 13, 27, 49}}};

TEST(SobolTest, DirectionNumbersFollowTheRecurrence) {
  for (int k = 0; k < kSobolBits; ++k) EXPECT_EQ(kSobolDirections[0][k], 1u << (31 - k));
  for (int d = 1; d < kSobolDimensions; ++d) {
    const Polynomial& p = kJoeKuo[d - 1];
    std::vector<uint32_t> v(kSobolBits);
    for (int k = 0; k < kSobolBits; ++k) {
      if (k < p.s) {
        v[k] = p.m[k] << (31 - k);
        continue;
      }
      v[k] = v[k - p.s] ^ (v[k - p.s] >> p.s);
      for (int j = 1; j < p.s; ++j) {
        if ((p.a >> (p.s - 1 - j)) & 1) v[k] ^= v[k - j];
      }
    }
    for (int k = 0; k < kSobolBits; ++k) {
      EXPECT_EQ(kSobolDirections[d][k], v[k]) << "dimension " << d << ", bit " << k;
    }
  }
}

TEST(SobolTest, FourDimensionsAtOnceAreEachDimension) {
  for (const uint32_t index : {0u, 1u, 6u, 1023u, 123456u, 0xffffffffu}) {
    for (int first = 0; first < kSobolDimensions; first += 4) {
      uint32_t x[4];
      SobolPoints4(index, first, x);
      for (int j = 0; j < 4; ++j) EXPECT_EQ(x[j], SobolPoint(index, first + j));
    }
  }
}

// Whether 2^m points, the first m_x binary digits of x and m - m_x of y, fill every box of
// that size once (an elementary interval of a (0, m, 2)-net).
bool FillsEveryBoxOnce(const std::vector<uint32_t>& x, const std::vector<uint32_t>& y, int m,
                       int m_x) {
  std::vector<int> count(size_t{1} << m, 0);
  for (size_t i = 0; i < x.size(); ++i) {
    const uint32_t bx = m_x > 0 ? x[i] >> (32 - m_x) : 0;
    const uint32_t by = m - m_x > 0 ? y[i] >> (32 - (m - m_x)) : 0;
    ++count[(bx << (m - m_x)) | by];
  }
  for (const int c : count) {
    if (c != 1) return false;
  }
  return true;
}

// The first 2^m points, and any 2^m from a multiple of 2^m: every dimension stratified into
// 2^m intervals, the first two a (0, m, 2)-net; scrambled alike.
TEST(SobolTest, PointsFormNetsScrambledOrNot) {
  constexpr int m = 10;
  for (const uint32_t start : {0u, 5u << m}) {
    for (const uint32_t seed : {0u, 0x1234567u, 0xdeadbeefu}) {
      std::vector<std::vector<uint32_t>> dims(kSobolDimensions);
      for (int d = 0; d < kSobolDimensions; ++d) {
        for (uint32_t i = start; i < start + (1u << m); ++i) {
          const uint32_t x = SobolPoint(i, d);
          dims[d].push_back(seed == 0 ? x : OwenScramble(x, MixBits(seed + d)));
        }
        EXPECT_TRUE(FillsEveryBoxOnce(dims[d], dims[d], m, m)) << "dimension " << d;
      }
      for (int m_x = 0; m_x <= m; ++m_x) {
        EXPECT_TRUE(FillsEveryBoxOnce(dims[0], dims[1], m, m_x))
            << "start " << start << " seed " << seed << " split " << m_x;
      }
    }
  }
}

// One point under many seeds lands uniformly: 16 equal bins get their share within 4
// standard deviations, and its first digits take both values.
TEST(SobolTest, ScrambledPointIsUniform) {
  constexpr int kSeeds = 1 << 16, kBins = 16;
  for (const uint32_t x : {0u, 0x80000000u, 0x12345678u}) {
    std::vector<int> bins(kBins, 0);
    for (int s = 0; s < kSeeds; ++s) ++bins[OwenScramble(x, MixBits(s)) >> 28];
    const double expected = static_cast<double>(kSeeds) / kBins;
    for (const int b : bins) EXPECT_NEAR(b, expected, 4 * std::sqrt(expected)) << x;
  }
}

// A smooth integral over the first four dimensions of a path's draws, E[u0 u1 + sin(pi u2)
// u3], by 1024 paths per batch in 64 batches: the batches' scatter is far below that of
// pseudo-random draws (about 1024^-1/2 against ~1024^-1 or better), and the mean within 3
// standard errors of the exact value.
TEST(SobolTest, QuasiRandomDrawsCutTheErrorOfASmoothIntegral) {
  constexpr int kBatches = 64, kPaths = 1024;
  const double exact = 0.25 + 1.0 / M_PI;
  const auto scatter = [&](Sequence sequence, double* mean) {
    std::vector<double> estimates;
    for (int b = 0; b < kBatches; ++b) {
      double sum = 0;
      const uint64_t first = static_cast<uint64_t>(b) * kPaths;
      for (uint64_t p = first; p < first + kPaths; ++p) {
        const Uniform4 u = PathRandom(7, 3, p, sequence, first).Draw(0, 0);
        sum += u.u[0] * u.u[1] + std::sin(M_PI * u.u[2]) * u.u[3];
      }
      estimates.push_back(sum / kPaths);
    }
    *mean = 0;
    for (const double e : estimates) *mean += e / kBatches;
    double variance = 0;
    for (const double e : estimates) variance += (e - *mean) * (e - *mean) / (kBatches - 1);
    return variance;
  };
  double pseudo_mean = 0, sobol_mean = 0;
  const double pseudo = scatter(Sequence::kPseudoRandom, &pseudo_mean);
  const double sobol = scatter(Sequence::kSobol, &sobol_mean);
  std::printf("smooth integral: variance per batch %.3g pseudo-random, %.3g Sobol (%.0f times)\n",
              pseudo, sobol, pseudo / sobol);
  EXPECT_GT(pseudo / sobol, 50.0);
  EXPECT_NEAR(sobol_mean, exact, 3 * std::sqrt(sobol / kBatches));
  EXPECT_NEAR(pseudo_mean, exact, 3 * std::sqrt(pseudo / kBatches));
}

// The quasi-random draws are a pure function of their inputs; other batches are other
// randomizations; draws beyond the first vertices and purposes are the pseudo-random ones.
TEST(SobolTest, PathDrawsAreQuasiRandomWhereSaid) {
  const PathRandom a(42, 3, 1000, Sequence::kSobol, 900), b(42, 3, 1000, Sequence::kSobol, 900);
  const PathRandom pseudo(42, 3, 1000);
  for (uint32_t vertex = 0; vertex < 4; ++vertex) {
    for (uint32_t purpose = 0; purpose < 3; ++purpose) {
      const Uniform4 x = a.Draw(vertex, purpose), y = b.Draw(vertex, purpose);
      const Uniform4 z = pseudo.Draw(vertex, purpose);
      const bool quasi = vertex < kQuasiRandomVertices && purpose < kQuasiRandomPurposes;
      for (int k = 0; k < 4; ++k) {
        EXPECT_EQ(x.u[k], y.u[k]);
        EXPECT_EQ(x.u[k] == z.u[k], !quasi) << vertex << " " << purpose << " " << k;
      }
    }
  }
  // The same point of another batch (or stream, or seed) is scrambled otherwise
  const Uniform4 x = a.Draw(0, 0);
  for (const PathRandom& other : {PathRandom(42, 3, 1100, Sequence::kSobol, 1000),
                                  PathRandom(42, 4, 1000, Sequence::kSobol, 900),
                                  PathRandom(43, 3, 1000, Sequence::kSobol, 900)}) {
    const Uniform4 y = other.Draw(0, 0);
    for (int k = 0; k < 4; ++k) EXPECT_NE(x.u[k], y.u[k]);
  }
}

}  // namespace
}  // namespace fenestra
