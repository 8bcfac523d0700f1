#include "core/geometry/mesh.h"

namespace fenestra {

void TriangleMesh::Append(const TriangleMesh& other) {
  const uint32_t part_offset = static_cast<uint32_t>(part_names.size());
  part_names.insert(part_names.end(), other.part_names.begin(), other.part_names.end());
  vertices.insert(vertices.end(), other.vertices.begin(), other.vertices.end());
  material.insert(material.end(), other.material.begin(), other.material.end());
  side.insert(side.end(), other.side.begin(), other.side.end());
  for (uint32_t p : other.part) part.push_back(p + part_offset);
}

}  // namespace fenestra
