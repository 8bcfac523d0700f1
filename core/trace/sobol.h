#pragma once

// Owen-scrambled Sobol points, the quasi-random part of a path's draws (philox.h,
// PathRandom; core/README.md, "Quasi-random sampling").
//
// - The Sobol sequence in its first kSobolDimensions dimensions: dimension 0 is van der
//   Corput's, dimensions 1 to 15 take the primitive polynomials and initial direction
//   numbers of Joe & Kuo (2008, "Constructing Sobol sequences with better two-dimensional
//   projections", their table's d = 2 to 16). Point i in dimension d is the XOR of the
//   direction numbers v[d][k] of the bits k set in i; any 2^m consecutive points from a
//   multiple of 2^m form a (t, m, s)-net, the first two dimensions a (0, m, 2)-net.
// - Each dimension scrambled on its own by a nested uniform (Owen) scramble drawn from a
//   hash: bit k of a point is flipped by a function of its bits above k alone, so the
//   scrambled points keep the nets and each is uniform on [0, 1) (Burley 2020, "Practical
//   hash-based Owen scrambling", after Laine & Karras 2011).
// The tests check the table against the recurrence from Joe & Kuo's parameters, the nets
// and the scramble's uniformity.
#include <cstdint>

#include "core/common/cpu_gpu.h"

namespace fenestra {

inline constexpr int kSobolDimensions = 16;
inline constexpr int kSobolBits = 32;

// v[d][k]: the direction number of index bit k in dimension d (bit 31 the first binary digit).
#define FENESTRA_SOBOL_DIRECTIONS                                                             \
  {                                                                                           \
    {0x80000000, 0x40000000, 0x20000000, 0x10000000, 0x08000000, 0x04000000, 0x02000000,      \
     0x01000000, 0x00800000, 0x00400000, 0x00200000, 0x00100000, 0x00080000, 0x00040000,      \
     0x00020000, 0x00010000, 0x00008000, 0x00004000, 0x00002000, 0x00001000, 0x00000800,      \
     0x00000400, 0x00000200, 0x00000100, 0x00000080, 0x00000040, 0x00000020, 0x00000010,      \
     0x00000008, 0x00000004, 0x00000002, 0x00000001},                                         \
        {0x80000000, 0xc0000000, 0xa0000000, 0xf0000000, 0x88000000, 0xcc000000, 0xaa000000,  \
         0xff000000, 0x80800000, 0xc0c00000, 0xa0a00000, 0xf0f00000, 0x88880000, 0xcccc0000,  \
         0xaaaa0000, 0xffff0000, 0x80008000, 0xc000c000, 0xa000a000, 0xf000f000, 0x88008800,  \
         0xcc00cc00, 0xaa00aa00, 0xff00ff00, 0x80808080, 0xc0c0c0c0, 0xa0a0a0a0, 0xf0f0f0f0,  \
         0x88888888, 0xcccccccc, 0xaaaaaaaa, 0xffffffff},                                     \
        {0x80000000, 0xc0000000, 0x60000000, 0x90000000, 0xe8000000, 0x5c000000, 0x8e000000,  \
         0xc5000000, 0x68800000, 0x9cc00000, 0xee600000, 0x55900000, 0x80680000, 0xc09c0000,  \
         0x60ee0000, 0x90550000, 0xe8808000, 0x5cc0c000, 0x8e606000, 0xc5909000, 0x6868e800,  \
         0x9c9c5c00, 0xeeee8e00, 0x5555c500, 0x8000e880, 0xc0005cc0, 0x60008e60, 0x9000c590,  \
         0xe8006868, 0x5c009c9c, 0x8e00eeee, 0xc5005555},                                     \
        {0x80000000, 0xc0000000, 0x20000000, 0x50000000, 0xf8000000, 0x74000000, 0xa2000000,  \
         0x93000000, 0xd8800000, 0x25400000, 0x59e00000, 0xe6d00000, 0x78080000, 0xb40c0000,  \
         0x82020000, 0xc3050000, 0x208f8000, 0x51474000, 0xfbea2000, 0x75d93000, 0xa0858800,  \
         0x914e5400, 0xdbe79e00, 0x25db6d00, 0x58800080, 0xe54000c0, 0x79e00020, 0xb6d00050,  \
         0x800800f8, 0xc00c0074, 0x200200a2, 0x50050093},                                     \
        {0x80000000, 0x40000000, 0x20000000, 0xb0000000, 0xf8000000, 0xdc000000, 0x7a000000,  \
         0x9d000000, 0x5a800000, 0x2fc00000, 0xa1600000, 0xf0b00000, 0xda880000, 0x6fc40000,  \
         0x81620000, 0x40bb0000, 0x22878000, 0xb3c9c000, 0xfb65a000, 0xddb2d000, 0x78022800,  \
         0x9c0b3c00, 0x5a0fb600, 0x2d0ddb00, 0xa2878080, 0xf3c9c040, 0xdb65a020, 0x6db2d0b0,  \
         0x800228f8, 0x400b3cdc, 0x200fb67a, 0xb00ddb9d},                                     \
        {0x80000000, 0x40000000, 0x60000000, 0x30000000, 0xc8000000, 0x24000000, 0x56000000,  \
         0xfb000000, 0xe0800000, 0x70400000, 0xa8600000, 0x14300000, 0x9ec80000, 0xdf240000,  \
         0xb6d60000, 0x8bbb0000, 0x48008000, 0x64004000, 0x36006000, 0xcb003000, 0x2880c800,  \
         0x54402400, 0xfe605600, 0xef30fb00, 0x7e48e080, 0xaf647040, 0x1eb6a860, 0x9f8b1430,  \
         0xd6c81ec8, 0xbb249f24, 0x80d6d6d6, 0x40bbbbbb},                                     \
        {0x80000000, 0xc0000000, 0xa0000000, 0xd0000000, 0x58000000, 0x94000000, 0x3e000000,  \
         0xe3000000, 0xbe800000, 0x23c00000, 0x1e200000, 0xf3100000, 0x46780000, 0x67840000,  \
         0x78460000, 0x84670000, 0xc6788000, 0xa784c000, 0xd846a000, 0x5467d000, 0x9e78d800,  \
         0x33845400, 0xe6469e00, 0xb7673300, 0x20f86680, 0x104477c0, 0xf8668020, 0x4477c010,  \
         0x668020f8, 0x77c01044, 0x8020f866, 0xc0104477},                                     \
        {0x80000000, 0x40000000, 0xa0000000, 0x50000000, 0x88000000, 0x24000000, 0x12000000,  \
         0x2d000000, 0x76800000, 0x9e400000, 0x08200000, 0x64100000, 0xb2280000, 0x7d140000,  \
         0xfea20000, 0xba490000, 0x1a248000, 0x491b4000, 0xc4b5a000, 0xe3739000, 0xf6800800,  \
         0xde400400, 0xa8200a00, 0x34100500, 0x3a280880, 0x59140240, 0xeca20120, 0x974902d0,  \
         0x6ca48768, 0xd75b49e4, 0xcc95a082, 0x87639641},                                     \
        {0x80000000, 0x40000000, 0xa0000000, 0x50000000, 0x28000000, 0xd4000000, 0x6a000000,  \
         0x71000000, 0x38800000, 0x58400000, 0xea200000, 0x31100000, 0x98a80000, 0x08540000,  \
         0xc22a0000, 0xe5250000, 0xf2b28000, 0x79484000, 0xfaa42000, 0xbd731000, 0x18a80800,  \
         0x48540400, 0x622a0a00, 0xb5250500, 0xdab28280, 0xad484d40, 0x90a426a0, 0xcc731710,  \
         0x20280b88, 0x10140184, 0x880a04a2, 0x84350611},                                     \
        {0x80000000, 0x40000000, 0xe0000000, 0xb0000000, 0x98000000, 0x94000000, 0x8a000000,  \
         0x5b000000, 0x33800000, 0xd9c00000, 0x72200000, 0x3f100000, 0xc1b80000, 0xa6ec0000,  \
         0x53860000, 0x29f50000, 0x0a3a8000, 0x1b2ac000, 0xd392e000, 0x69ff7000, 0xea380800,  \
         0xab2c0400, 0x4ba60e00, 0xfde50b00, 0x60028980, 0xf006c940, 0x7834e8a0, 0x241a75b0,  \
         0x123a8b38, 0xcf2ac99c, 0xb992e922, 0x82ff78f1},                                     \
        {0x80000000, 0x40000000, 0xa0000000, 0x10000000, 0x08000000, 0x6c000000, 0x9e000000,  \
         0x23000000, 0x57800000, 0xadc00000, 0x7fa00000, 0x91d00000, 0x49880000, 0xced40000,  \
         0x880a0000, 0x2c0f0000, 0x3e0d8000, 0x3317c000, 0x5fb06000, 0xc1f8b000, 0xe18d8800,  \
         0xb2d7c400, 0x1e106a00, 0x6328b100, 0xf7858880, 0xbdc3c2c0, 0x77ba63e0, 0xfdf7b330,  \
         0xd7800df8, 0xedc0081c, 0xdfa0041a, 0x81d00a2d},                                     \
        {0x80000000, 0x40000000, 0x20000000, 0x30000000, 0x58000000, 0xac000000, 0x96000000,  \
         0x2b000000, 0xd4800000, 0x09400000, 0xe2a00000, 0x52500000, 0x4e280000, 0xc71c0000,  \
         0x629e0000, 0x12670000, 0x6e138000, 0xf731c000, 0x3a98a000, 0xbe449000, 0xf83b8800,  \
         0xdc2dc400, 0xee06a200, 0xb7239300, 0x1aa80d80, 0x8e5c0ec0, 0xa03e0b60, 0x703701b0,  \
         0x783b88c8, 0x9c2dca54, 0xce06a74a, 0x87239795},                                     \
        {0x80000000, 0xc0000000, 0xa0000000, 0x50000000, 0xf8000000, 0x8c000000, 0xe2000000,  \
         0x33000000, 0x0f800000, 0x21400000, 0x95a00000, 0x5e700000, 0xd8080000, 0x1c240000,  \
         0xba160000, 0xef370000, 0x15868000, 0x9e6fc000, 0x781b6000, 0x4c349000, 0x420e8800,  \
         0x630bcc00, 0xf7ad6a00, 0xad739500, 0x77800780, 0x6d4004c0, 0xd7a00420, 0x3d700630,  \
         0x2f880f78, 0xb1640ad4, 0xcdb6077a, 0x824706d7},                                     \
        {0x80000000, 0xc0000000, 0x60000000, 0x90000000, 0x38000000, 0xc4000000, 0x42000000,  \
         0xa3000000, 0xf1800000, 0xaa400000, 0xfce00000, 0x85100000, 0xe0080000, 0x500c0000,  \
         0x58060000, 0x54090000, 0x7a038000, 0x670c4000, 0xb3842000, 0x094a3000, 0x0d6f1800,  \
         0x2f5aa400, 0x1ce7ce00, 0xd5145100, 0xb8000080, 0x040000c0, 0x22000060, 0x33000090,  \
         0xc9800038, 0x6e4000c4, 0xbee00042, 0x261000a3},                                     \
        {0x80000000, 0x40000000, 0x20000000, 0xf0000000, 0xa8000000, 0x54000000, 0x9a000000,  \
         0x9d000000, 0x1e800000, 0x5cc00000, 0x7d200000, 0x8d100000, 0x24880000, 0x71c40000,  \
         0xeba20000, 0x75df0000, 0x6ba28000, 0x35d14000, 0x4ba3a000, 0xc5d2d000, 0xe3a16800,  \
         0x91db8c00, 0x79aef200, 0x0cdf4100, 0x672a8080, 0x50154040, 0x1a01a020, 0xdd0dd0f0,  \
         0x3e83e8a8, 0xaccacc54, 0xd52d529a, 0xd91d919d},                                     \
    {                                                                                         \
      0x80000000, 0xc0000000, 0x20000000, 0xd0000000, 0xd8000000, 0xc4000000, 0x46000000,     \
          0x85000000, 0xa5800000, 0x76c00000, 0xada00000, 0x6ab00000, 0x2da80000, 0xaabc0000, \
          0x0daa0000, 0x7ab10000, 0xd5a78000, 0xbebd4000, 0x93a3e000, 0x3bb51000, 0x3629b800, \
          0x4d727c00, 0x9b836200, 0x27c4d700, 0xb629b880, 0x8d727cc0, 0xbb836220, 0xf7c4d7d0, \
          0x6e29b858, 0x49727c04, 0xfd836266, 0x72c4d755                                      \
    }                                                                                         \
  }

inline constexpr uint32_t kSobolDirections[kSobolDimensions][kSobolBits] =
    FENESTRA_SOBOL_DIRECTIONS;
#if defined(__CUDACC__)
static __constant__ uint32_t kSobolDirectionsOnGpu[kSobolDimensions][kSobolBits] =
    FENESTRA_SOBOL_DIRECTIONS;
#endif

// Point `index` of the unscrambled sequence in dimension `d` (0 <= d < kSobolDimensions), as
// 32 binary digits.
FENESTRA_CPU_GPU inline uint32_t SobolPoint(uint32_t index, int d) {
  uint32_t x = 0;
  for (int k = 0; index != 0; index >>= 1, ++k) {
#if defined(__CUDA_ARCH__)
    if (index & 1u) x ^= kSobolDirectionsOnGpu[d][k];
#else
    if (index & 1u) x ^= kSobolDirections[d][k];
#endif
  }
  return x;
}

// Point `index` in dimensions `first` to first + 3 (first a multiple of 4), into x[0..3]:
// SobolPoint of each, in one pass over the index's bits.
FENESTRA_CPU_GPU inline void SobolPoints4(uint32_t index, int first, uint32_t x[4]) {
  x[0] = x[1] = x[2] = x[3] = 0;
  for (int k = 0; index != 0; index >>= 1, ++k) {
    if ((index & 1u) == 0) continue;
    for (int j = 0; j < 4; ++j) {
#if defined(__CUDA_ARCH__)
      x[j] ^= kSobolDirectionsOnGpu[first + j][k];
#else
      x[j] ^= kSobolDirections[first + j][k];
#endif
    }
  }
}

FENESTRA_CPU_GPU inline uint32_t ReverseBits(uint32_t x) {
#if defined(__CUDA_ARCH__)
  return __brev(x);
#else
  x = ((x >> 1) & 0x55555555u) | ((x & 0x55555555u) << 1);
  x = ((x >> 2) & 0x33333333u) | ((x & 0x33333333u) << 2);
  x = ((x >> 4) & 0x0F0F0F0Fu) | ((x & 0x0F0F0F0Fu) << 4);
  x = ((x >> 8) & 0x00FF00FFu) | ((x & 0x00FF00FFu) << 8);
  return (x >> 16) | (x << 16);
#endif
}

// The nested uniform scramble of `x` (32 binary digits) under `seed`. With the digits
// reversed, each step changes a bit by the bits below it alone: adding, multiplying by an
// odd number and XOR with a multiple by an even one.
FENESTRA_CPU_GPU inline uint32_t OwenScramble(uint32_t x, uint32_t seed) {
  x = ReverseBits(x);
  x ^= x * 0x3d20adeau;
  x += seed;
  x *= (seed >> 16) | 1u;
  x ^= x * 0x05526c56u;
  x ^= x * 0x53a22864u;
  return ReverseBits(x);
}

// A well-mixed 32-bit function of `x` (the finalizer of MurmurHash3), for scramble seeds.
FENESTRA_CPU_GPU inline uint32_t MixBits(uint32_t x) {
  x ^= x >> 16;
  x *= 0x85ebca6bu;
  x ^= x >> 13;
  x *= 0xc2b2ae35u;
  x ^= x >> 16;
  return x;
}

}  // namespace fenestra
