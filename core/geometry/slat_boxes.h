#pragma once

// A Venetian blind's slats as boxes in double precision, for the host and the GPU alike: the
// mesh GenerateBlind makes and the slats the replays trace from their layout
// (core/trace/local_slats.h) take their corners and faces from here, so both hold the very
// same triangles.
#include <stdint.h>

#include "core/common/cpu_gpu.h"
#include "core/common/vec3.h"

namespace fenestra {

struct SlatBoxes {
  Vec3d center, stack;  // world: the middle of the slats' axes, and the unit stacking axis
  Vec3d half_length, half_width, half_thickness;  // a slat's half extents, as vectors
  double pitch = 0;
  int count = 0;

  // Corner i of slat k (0 <= k < count): bits 0, 1 and 2 of i take the + side of the half
  // length, width and thickness.
  FENESTRA_CPU_GPU Vec3d Corner(int k, int i) const {
    const double offset = (k - 0.5 * (count - 1)) * pitch;
    const Vec3d middle = center + stack * offset;
    return middle + half_length * ((i & 1) ? 1.0 : -1.0) + half_width * ((i & 2) ? 1.0 : -1.0) +
           half_thickness * ((i & 4) ? 1.0 : -1.0);
  }

  // Corner j (0..3, around the face) of face f: faces 0 and 1 are the -/+ ends along the
  // length, 2 and 3 the -/+ edges across the width, 4 and 5 the -/+ sides across the
  // thickness. A face is meshed as the triangles (0, 1, 2) and (0, 2, 3).
  FENESTRA_CPU_GPU static int FaceCorner(int f, int j) {
    constexpr uint16_t kFaces[6] = {0 | 2 << 3 | 6 << 6 | 4 << 9, 1 | 5 << 3 | 7 << 6 | 3 << 9,
                                    0 | 4 << 3 | 5 << 6 | 1 << 9, 2 | 3 << 3 | 7 << 6 | 6 << 9,
                                    0 | 1 << 3 | 3 << 6 | 2 << 9, 4 | 6 << 3 | 7 << 6 | 5 << 9};
    return (kFaces[f] >> (3 * j)) & 7;
  }
};

}  // namespace fenestra
