#pragma once

#include <cstddef>
#include <vector>

#include "absl/status/statusor.h"
#include "core/common/vec3.h"
#include "core/geometry/mesh.h"
#include "core/trace/path.h"

namespace fenestra {

// The mesh as every tracer backend sees it. Vertices are translated by the bounding-box
// centre in double before the conversion to float, so a scene far from the world origin
// keeps the precision of one near it.
struct TraceGeometry {
  Vec3d origin{0, 0, 0};        // world position of the local frame's origin [m]
  std::vector<Vec3f> vertices;  // 3 per triangle, local frame [m]
  std::vector<uint32_t> triangle_material;
  std::vector<TraceMaterial> materials;
  size_t degenerate_triangles = 0;  // zero area in float: kept, but never hit

  size_t TriangleCount() const { return triangle_material.size(); }
  // A world point in the local frame.
  Vec3f ToLocal(Vec3d world) const;
  SurfaceTable Surfaces() const { return {materials.data(), triangle_material.data()}; }
};

// `material` as the tracer sees it. InvalidArgument "material '<name>': ..." where its parts
// break CheckMaterialParts's rules (core/geometry/material.h).
absl::StatusOr<TraceMaterial> ToTraceMaterial(const Material& material);

// Whether triangle `i` of `geometry` has a nonzero, finite area in float.
bool HasArea(const TraceGeometry& geometry, size_t i);

// Checks and converts `mesh` and `materials`. InvalidArgument for non-finite vertices,
// material indices out of range, reflectance outside [0, 1), transmittance above 1, or
// reflectance + transmittance above 1. The local frame's origin is `origin` when given,
// else the centre of the mesh's bounding box.
absl::StatusOr<TraceGeometry> PrepareTraceGeometry(const TriangleMesh& mesh,
                                                   const std::vector<Material>& materials,
                                                   const Vec3d* origin = nullptr);

}  // namespace fenestra
