#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/common/vec3.h"

namespace fenestra {

// Which stage of the two-stage method sees a triangle.
enum class Side : uint8_t { kIndoor, kOutdoor };

// A Lambertian material.
struct Material {
  std::string name;
  double reflectance = 0;     // diffuse reflectance in [0, 1)
  double transmittance = -1;  // glazing transmittance in [0, 1]; < 0 = opaque
};

// Assembled triangle soup: triangle i has vertices 3i, 3i+1, 3i+2 [m].
struct TriangleMesh {
  std::vector<Vec3d> vertices;
  std::vector<uint32_t> material;  // per triangle: index into the scene's materials
  std::vector<Side> side;          // per triangle
  std::vector<uint32_t> part;      // per triangle: index into part_names
  std::vector<std::string> part_names;

  size_t TriangleCount() const { return material.size(); }
  // Appends triangle (a, b, c) of `part_index`.
  void Add(Vec3d a, Vec3d b, Vec3d c, uint32_t material_index, Side s, uint32_t part_index) {
    vertices.insert(vertices.end(), {a, b, c});
    material.push_back(material_index);
    side.push_back(s);
    part.push_back(part_index);
  }
  // Appends every triangle of `other` (same material table), renumbering its parts.
  void Append(const TriangleMesh& other);
};

}  // namespace fenestra
