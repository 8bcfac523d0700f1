#pragma once

#include <map>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/geometry/mesh.h"
#include "core/geometry/scene.h"

namespace fenestra {

// Triangles of an OBJ file with the group (or object) name each came from.
struct ObjTriangles {
  std::vector<Vec3d> vertices;     // 3 per triangle [m]
  std::vector<std::string> group;  // per triangle
};

// Reads and triangulates an OBJ file. Errors name the file and the problem (missing file,
// parse errors, indices out of range, non-finite coordinates, no faces).
absl::StatusOr<ObjTriangles> ReadObj(const std::string& path);

// Writes `mesh` as OBJ with one group per material (named after it). Atomic: on failure
// no file is left at `path`.
absl::Status WriteObj(const std::string& path, const TriangleMesh& mesh,
                      const std::vector<Material>& materials);

// Writes the scene's complete geometry at `design` (AssembleMesh: the blind included) as
// WriteObj does; returns the number of triangles written.
absl::StatusOr<size_t> WriteSceneObj(const std::string& path, const Scene& scene,
                                     const BlindDesign& design);

}  // namespace fenestra
