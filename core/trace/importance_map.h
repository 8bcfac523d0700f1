// Importance of surface points for weight windows: a sparse grid of cubic cells (split by
// the side the surface faces),
// stored in an open-addressing hash table that CPU and GPU code read alike.
//
// Weight windows: Booth, "A Sample Problem for Variance Reduction in MCNP" (LA-10363-MS,
// 1985), and Hendricks and Booth, "MCNP Variance Reduction Overview" (1985). The importance
// of a point is the mean score a path leaving it with weight 1 goes on to collect, learned
// from pilot paths (TraceImportancePilotCpu).
#pragma once

#include <math.h>
#include <stdint.h>

#include "core/common/cpu_gpu.h"
#include "core/common/vec3.h"

namespace fenestra {

// An empty slot's key (no cell has it: keys use 63 bits).
inline constexpr uint64_t kEmptyCellKey = ~0ull;

// The key of the cell holding `p` (local frame) for cells of 1 / inverse_cell_m metres,
// together with the side a surface there faces: the axis and sign of the largest component
// of `normal` (the side the path leaves on). The two faces of a thin wall, or a wall and
// the floor in one cell, thus keep importances of their own.
FENESTRA_CPU_GPU inline uint64_t CellKey(Vec3f p, Vec3f normal, float inverse_cell_m) {
  constexpr double kOffset = 524288.0;  // 2^19: cell coordinates in [0, 2^20)
  const float c[3] = {p.x, p.y, p.z};
  uint64_t key = 0;
  for (int axis = 0; axis < 3; ++axis) {
    // Truncation of a positive value is its floor
    double cell = static_cast<double>(c[axis]) * inverse_cell_m + kOffset;
    cell = cell < 0.0 ? 0.0 : (cell > 2.0 * kOffset - 1.0 ? 2.0 * kOffset - 1.0 : cell);
    key = (key << 20) | static_cast<uint64_t>(cell);
  }
  const float ax = fabsf(normal.x), ay = fabsf(normal.y), az = fabsf(normal.z);
  const uint64_t side = ax >= ay && ax >= az ? (normal.x > 0 ? 0 : 1)
                        : ay >= az           ? (normal.y > 0 ? 2 : 3)
                                             : (normal.z > 0 ? 4 : 5);
  return (key << 3) | side;
}

// A 64-bit finalizer (splitmix64) to spread keys over the table.
FENESTRA_CPU_GPU inline uint64_t HashCellKey(uint64_t key) {
  key ^= key >> 30;
  key *= 0xbf58476d1ce4e5b9ull;
  key ^= key >> 27;
  key *= 0x94d049bb133111ebull;
  return key ^ (key >> 31);
}

struct ImportanceMap {
  float inverse_cell_m;  // 1 / cell edge [1/m]
  uint32_t mask;         // table capacity - 1 (capacity a power of two, never full)
  const uint64_t* keys;  // per slot: a cell key or kEmptyCellKey
  const float* values;   // per slot: the cell's importance
  float fallback;        // importance of cells not in the table

  // The importance at `p` on a surface facing `normal`.
  FENESTRA_CPU_GPU float Lookup(Vec3f p, Vec3f normal) const {
    const uint64_t key = CellKey(p, normal, inverse_cell_m);
    uint32_t slot = static_cast<uint32_t>(HashCellKey(key)) & mask;
    for (uint32_t probe = 0; probe <= mask; ++probe) {
      const uint64_t k = keys[slot];
      if (k == key) return values[slot];
      if (k == kEmptyCellKey) break;
      slot = (slot + 1) & mask;
    }
    return fallback;
  }
};

}  // namespace fenestra
