// Small meshes built in code for the tracer and daylight-coefficient tests.
#pragma once

#include <cstdint>

#include "core/common/vec3.h"
#include "core/geometry/mesh.h"

namespace fenestra {
namespace testing_meshes {

// Quad a-b-c-d (planar, convex) as two triangles.
inline void AddQuad(TriangleMesh& mesh, Vec3d a, Vec3d b, Vec3d c, Vec3d d, uint32_t material) {
  mesh.Add(a, b, c, material, Side::kIndoor, 0);
  mesh.Add(a, c, d, material, Side::kIndoor, 0);
}

// The six faces of the axis-aligned box [lo, hi].
inline void AddBox(TriangleMesh& mesh, Vec3d lo, Vec3d hi, uint32_t material) {
  const Vec3d p[8] = {{lo.x, lo.y, lo.z}, {hi.x, lo.y, lo.z}, {hi.x, hi.y, lo.z},
                      {lo.x, hi.y, lo.z}, {lo.x, lo.y, hi.z}, {hi.x, lo.y, hi.z},
                      {hi.x, hi.y, hi.z}, {lo.x, hi.y, hi.z}};
  AddQuad(mesh, p[0], p[1], p[2], p[3], material);  // bottom
  AddQuad(mesh, p[4], p[5], p[6], p[7], material);  // top
  AddQuad(mesh, p[0], p[1], p[5], p[4], material);  // south
  AddQuad(mesh, p[3], p[2], p[6], p[7], material);  // north
  AddQuad(mesh, p[0], p[3], p[7], p[4], material);  // west
  AddQuad(mesh, p[1], p[2], p[6], p[5], material);  // east
}

// The horizontal square of half side `half` centred on (cx, cy) at height z.
inline void AddSquare(TriangleMesh& mesh, double cx, double cy, double half, double z,
                      uint32_t material) {
  AddQuad(mesh, {cx - half, cy - half, z}, {cx + half, cy - half, z}, {cx + half, cy + half, z},
          {cx - half, cy + half, z}, material);
}

// Every vertex moved by `offset`.
inline TriangleMesh Translated(TriangleMesh mesh, Vec3d offset) {
  for (Vec3d& v : mesh.vertices) v = v + offset;
  return mesh;
}

}  // namespace testing_meshes
}  // namespace fenestra
