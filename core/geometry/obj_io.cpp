#include "core/geometry/obj_io.h"

#include <tiny_obj_loader.h>

#include <cmath>
#include <filesystem>
#include <sstream>

#include "absl/strings/str_cat.h"
#include "core/common/atomic_file.h"

namespace fenestra {

absl::StatusOr<ObjTriangles> ReadObj(const std::string& path) {
  if (!std::filesystem::is_regular_file(path)) {
    return absl::NotFoundError(absl::StrCat(path, ": OBJ file not found"));
  }
  tinyobj::ObjReaderConfig config;
  config.triangulate = true;
  config.vertex_color = false;
  tinyobj::ObjReader reader;
  if (!reader.ParseFromFile(path, config) || !reader.Error().empty()) {
    std::string why = reader.Error();
    while (!why.empty() && why.back() == '\n') why.pop_back();
    return absl::InvalidArgumentError(absl::StrCat(path, ": malformed OBJ: ", why));
  }
  const auto& positions = reader.GetAttrib().vertices;
  for (size_t i = 0; i < positions.size(); ++i) {
    if (!std::isfinite(positions[i])) {
      return absl::InvalidArgumentError(
          absl::StrCat(path, ": malformed OBJ: vertex ", i / 3 + 1, " is not finite"));
    }
  }
  ObjTriangles out;
  const long vertex_count = static_cast<long>(positions.size() / 3);
  for (const tinyobj::shape_t& shape : reader.GetShapes()) {
    const auto& mesh = shape.mesh;
    size_t index = 0;
    for (size_t f = 0; f < mesh.num_face_vertices.size(); ++f) {
      const int n = mesh.num_face_vertices[f];
      if (n != 3) {
        return absl::InvalidArgumentError(absl::StrCat(path, ": malformed OBJ: face ", f + 1,
                                                       " of group '", shape.name, "' has ", n,
                                                       " vertices after triangulation"));
      }
      for (int k = 0; k < 3; ++k) {
        const int v = mesh.indices[index + k].vertex_index;
        if (v < 0 || v >= vertex_count) {
          return absl::InvalidArgumentError(
              absl::StrCat(path, ": malformed OBJ: face ", f + 1, " of group '", shape.name,
                           "' refers to vertex ", v + 1, " of ", vertex_count));
        }
        out.vertices.push_back({positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]});
      }
      out.group.push_back(shape.name);
      index += n;
    }
  }
  if (out.group.empty()) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": malformed OBJ: no faces"));
  }
  return out;
}

absl::Status WriteObj(const std::string& path, const TriangleMesh& mesh,
                      const std::vector<Material>& materials) {
  return WriteFileAtomically(path, [&](std::ostream& out) {
    out << "# fenestra scene export: " << mesh.TriangleCount() << " triangles\n";
    out.precision(10);
    for (const Vec3d& v : mesh.vertices) out << "v " << v.x << ' ' << v.y << ' ' << v.z << '\n';
    for (uint32_t m = 0; m < materials.size(); ++m) {
      bool any = false;
      for (size_t t = 0; t < mesh.TriangleCount(); ++t) {
        if (mesh.material[t] != m) continue;
        if (!any) out << "g " << materials[m].name << "\nusemtl " << materials[m].name << '\n';
        any = true;
        out << "f " << 3 * t + 1 << ' ' << 3 * t + 2 << ' ' << 3 * t + 3 << '\n';
      }
    }
    return absl::OkStatus();
  });
}

absl::StatusOr<size_t> WriteSceneObj(const std::string& path, const Scene& scene,
                                     const BlindDesign& design) {
  const TriangleMesh mesh = AssembleMesh(scene, design);
  const absl::Status written = WriteObj(path, mesh, scene.materials);
  if (!written.ok()) return written;
  return mesh.TriangleCount();
}

}  // namespace fenestra
