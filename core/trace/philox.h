// Philox4x32-10 counter-based random numbers, identical on CPU and GPU.
//
// Salmon, Moraes, Dror and Shaw, "Parallel Random Numbers: As Easy as 1, 2, 3", SC'11
// (Random123). Multipliers 0xD2511F53 and 0xCD9E8D57, Weyl key increments 0x9E3779B9 and
// 0xBB67AE85, ten rounds. Output is a pure function of the 128-bit counter and 64-bit key,
// so a path's numbers depend only on (seed, stream, path index, vertex, purpose).
#pragma once

#include <cstdint>

#include "core/common/cpu_gpu.h"
#include "core/trace/sobol.h"

namespace fenestra {

// The seed of every random stream where a run does not give one (a job's `seed`, the
// options of each stage and method, the search).
inline constexpr uint64_t kDefaultSeed = 1;

struct Philox4x32 {
  uint32_t v[4];
};

namespace philox_internal {

FENESTRA_CPU_GPU inline void MulHiLo(uint32_t a, uint32_t b, uint32_t* hi, uint32_t* lo) {
  const uint64_t product = static_cast<uint64_t>(a) * static_cast<uint64_t>(b);
  *hi = static_cast<uint32_t>(product >> 32);
  *lo = static_cast<uint32_t>(product);
}

}  // namespace philox_internal

// One Philox4x32-10 block: 4 random 32-bit words for `counter` under `key`.
FENESTRA_CPU_GPU inline Philox4x32 Philox4x32_10(Philox4x32 counter, uint32_t key0, uint32_t key1) {
  constexpr uint32_t kMul0 = 0xD2511F53u, kMul1 = 0xCD9E8D57u;
  constexpr uint32_t kWeyl0 = 0x9E3779B9u, kWeyl1 = 0xBB67AE85u;
  uint32_t c0 = counter.v[0], c1 = counter.v[1], c2 = counter.v[2], c3 = counter.v[3];
  for (int round = 0; round < 10; ++round) {
    if (round > 0) {
      key0 += kWeyl0;
      key1 += kWeyl1;
    }
    uint32_t hi0, lo0, hi1, lo1;
    philox_internal::MulHiLo(kMul0, c0, &hi0, &lo0);
    philox_internal::MulHiLo(kMul1, c2, &hi1, &lo1);
    c0 = hi1 ^ c1 ^ key0;
    c1 = lo1;
    c2 = hi0 ^ c3 ^ key1;
    c3 = lo0;
  }
  return {{c0, c1, c2, c3}};
}

// A uniform float in [0, 1) from the top 24 bits of `bits` (exactly representable).
FENESTRA_CPU_GPU inline float UniformFloat(uint32_t bits) {
  return static_cast<float>(bits >> 8) * (1.0f / 16777216.0f);
}

// Four uniforms in [0, 1).
struct Uniform4 {
  float u[4];
};

// How a path's first draws are made (Sampling.sequence): every draw pseudo-random, or those
// of the first kQuasiRandomVertices vertices and kQuasiRandomPurposes purposes quasi-random,
// from an Owen-scrambled Sobol sequence of its own per batch and stream (sobol.h).
enum class Sequence : uint8_t { kPseudoRandom = 0, kSobol = 1 };
inline constexpr uint32_t kQuasiRandomVertices = 2, kQuasiRandomPurposes = 2;
// The sequence where a run does not name one (Sampling.sequence).
inline constexpr Sequence kDefaultSequence = Sequence::kPseudoRandom;
static_assert(4 * kQuasiRandomVertices * kQuasiRandomPurposes == kSobolDimensions);

// The random stream of one path: counter = (path low, path high, stream, vertex << 4 |
// purpose), key = seed. `stream` is the sensor (or start cell) index. Every draw is a pure
// function of these, so CPU and GPU, any thread count and any scheduling see the same
// numbers, and designs of one optimization share them (common random numbers).
//
// With Sequence::kSobol a path is also point (path - batch_first) of its batch's sequence:
// its draws at vertex v < kQuasiRandomVertices for purpose p < kQuasiRandomPurposes are that
// point's dimensions 4 (v kQuasiRandomPurposes + p) to 4 (v kQuasiRandomPurposes + p) + 3,
// each dimension scrambled by a seed of (seed, stream, batch_first, dimension), so that the
// batches are independent randomizations; its other draws are the pseudo-random ones.
class PathRandom {
 public:
  FENESTRA_CPU_GPU PathRandom(uint64_t seed, uint32_t stream, uint64_t path)
      : key0_(static_cast<uint32_t>(seed)),
        key1_(static_cast<uint32_t>(seed >> 32)),
        path_lo_(static_cast<uint32_t>(path)),
        path_hi_(static_cast<uint32_t>(path >> 32)),
        stream_(stream) {}
  // Path `path` of the batch whose first path is `batch_first` (<= path, fewer than 2^32
  // before it), drawn as `sequence` says.
  FENESTRA_CPU_GPU PathRandom(uint64_t seed, uint32_t stream, uint64_t path, Sequence sequence,
                              uint64_t batch_first)
      : PathRandom(seed, stream, path) {
    if (sequence == Sequence::kSobol) point_ = static_cast<uint32_t>(path - batch_first);
  }

  // Four uniforms for path vertex `vertex` (0 = the start) and `purpose` (0..15).
  FENESTRA_CPU_GPU Uniform4 Draw(uint32_t vertex, uint32_t purpose) const {
    if (point_ != kNoPoint && vertex < kQuasiRandomVertices && purpose < kQuasiRandomPurposes) {
      return QuasiRandomDraw(4 * static_cast<int>(vertex * kQuasiRandomPurposes + purpose));
    }
    const Philox4x32 bits = Philox4x32_10(
        {{path_lo_, path_hi_, stream_, (vertex << 4) | (purpose & 15u)}}, key0_, key1_);
    return {{UniformFloat(bits.v[0]), UniformFloat(bits.v[1]), UniformFloat(bits.v[2]),
             UniformFloat(bits.v[3])}};
  }

  // The path index the draws belong to.
  FENESTRA_CPU_GPU uint64_t path() const {
    return (static_cast<uint64_t>(path_hi_) << 32) | path_lo_;
  }

 private:
  static constexpr uint32_t kNoPoint = 0xFFFFFFFFu;  // pseudo-random throughout

  // Dimensions first to first + 3 of the path's point, scrambled. Not inlined, so that the
  // pseudo-random draws' code stays as it is without it.
  FENESTRA_CPU_GPU FENESTRA_NOINLINE Uniform4 QuasiRandomDraw(int first) const {
    uint32_t x[4];
    SobolPoints4(point_, first, x);
    const uint64_t batch_first = path() - point_;
    const uint32_t scramble = MixBits(
        key0_ ^
        MixBits(key1_ ^ MixBits(stream_ ^ MixBits(static_cast<uint32_t>(batch_first >> 32) ^
                                                  MixBits(static_cast<uint32_t>(batch_first))))));
    Uniform4 u;
    for (int k = 0; k < 4; ++k) {
      const uint32_t seed = MixBits(scramble + 0x9E3779B9u * static_cast<uint32_t>(first + k));
      u.u[k] = UniformFloat(OwenScramble(x[k], seed));
    }
    return u;
  }

  uint32_t key0_, key1_, path_lo_, path_hi_, stream_;
  uint32_t point_ = kNoPoint;  // the point of its batch's sequence (kSobol)
};

}  // namespace fenestra
