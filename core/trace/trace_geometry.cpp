#include "core/trace/trace_geometry.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "absl/strings/str_cat.h"
#include "core/common/status_macros.h"
#include "core/geometry/material.h"
#include "core/trace/glass.h"

namespace fenestra {
namespace {

bool IsFinite(Vec3d v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

}  // namespace

Vec3f TraceGeometry::ToLocal(Vec3d world) const {
  const Vec3d d = world - origin;
  return {static_cast<float>(d.x), static_cast<float>(d.y), static_cast<float>(d.z)};
}

absl::StatusOr<TraceMaterial> ToTraceMaterial(const Material& material) {
  if (const absl::Status parts = CheckMaterialParts(material); !parts.ok()) {
    return absl::InvalidArgumentError(
        absl::StrCat("material '", material.name, "': ", parts.message()));
  }
  const double rho = material.reflectance, tau = std::max(material.transmittance, 0.0);
  TraceMaterial trace{static_cast<float>(rho), material.transmittance >= 0
                                                   ? static_cast<float>(material.transmittance)
                                                   : -1.0f};
  trace.specular = static_cast<float>(material.specular);
  trace.roughness = static_cast<float>(material.roughness);
  trace.through = static_cast<float>(material.through);
  trace.straight_scatters = material.kind == MaterialKind::kTrans;
  if (trace.specular > 0.0f && trace.roughness > kMirrorRoughness) {
    trace.energy = LobeEnergyOf(trace.roughness);
  }
  if (material.kind == MaterialKind::kGlass) {
    trace.glass = GlassPane::TransmissivityFor(static_cast<float>(tau));
  }
  return trace;
}

bool HasArea(const TraceGeometry& geometry, size_t i) {
  const Vec3f* v = &geometry.vertices[3 * i];
  const Vec3f n = Cross(v[1] - v[0], v[2] - v[0]);
  const float length_squared = Dot(n, n);
  return length_squared > 0.0f && std::isfinite(length_squared);
}

absl::StatusOr<TraceGeometry> PrepareTraceGeometry(const TriangleMesh& mesh,
                                                   const std::vector<Material>& materials,
                                                   const Vec3d* origin) {
  TraceGeometry geometry;
  // Check the materials
  for (size_t m = 0; m < materials.size(); ++m) {
    FENESTRA_ASSIGN_OR_RETURN(trace, ToTraceMaterial(materials[m]));
    geometry.materials.push_back(trace);
  }

  // Check the triangles and find the bounding box
  const size_t triangles = mesh.TriangleCount();
  if (mesh.vertices.size() != 3 * triangles) {
    return absl::InvalidArgumentError(
        absl::StrCat("mesh has ", mesh.vertices.size(), " vertices for ", triangles, " triangles"));
  }
  constexpr double kInf = std::numeric_limits<double>::infinity();
  Vec3d lo{kInf, kInf, kInf}, hi{-kInf, -kInf, -kInf};
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    const Vec3d v = mesh.vertices[i];
    if (!IsFinite(v)) {
      return absl::InvalidArgumentError(
          absl::StrCat("triangle ", i / 3, " has a non-finite vertex"));
    }
    lo = {std::min(lo.x, v.x), std::min(lo.y, v.y), std::min(lo.z, v.z)};
    hi = {std::max(hi.x, v.x), std::max(hi.y, v.y), std::max(hi.z, v.z)};
  }
  for (size_t t = 0; t < triangles; ++t) {
    if (mesh.material[t] >= materials.size()) {
      return absl::InvalidArgumentError(absl::StrCat("triangle ", t, " uses material ",
                                                     mesh.material[t], " of ", materials.size()));
    }
  }

  // Translate to the box centre in double, then convert
  if (origin != nullptr) {
    geometry.origin = *origin;
  } else if (triangles > 0) {
    geometry.origin = (lo + hi) * 0.5;
  }
  geometry.vertices.reserve(mesh.vertices.size());
  for (const Vec3d& v : mesh.vertices) geometry.vertices.push_back(geometry.ToLocal(v));
  geometry.triangle_material = mesh.material;
  for (size_t t = 0; t < triangles; ++t) {
    if (!HasArea(geometry, t)) ++geometry.degenerate_triangles;
  }
  return geometry;
}

}  // namespace fenestra
