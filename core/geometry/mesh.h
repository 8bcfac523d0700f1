#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/common/vec3.h"

namespace fenestra {

// Which stage of the two-stage method sees a triangle.
enum class Side : uint8_t { kIndoor, kOutdoor };

// How a scene gave a material: Lambertian (with plain glazing's transmittance) or one of
// Radiance's (grey; scene.proto's Plastic, Metal, Trans and Glass).
enum class MaterialKind : uint8_t { kLambertian, kPlastic, kMetal, kTrans, kGlass };

// A material by its parts (core/trace/scatter.h): what each part reflects or transmits.
// Radiance's plastic (colour c, specularity s, roughness a): reflectance c (1 - s), specular s;
// metal: reflectance c (1 - s), specular c s; trans (and transmissivity T, transmitted
// specular T_s): reflectance c (1 - s) (1 - T), specular s, through c (1 - s) T (1 - T_s),
// transmittance c (1 - s) T T_s; glass: transmittance at normal incidence, the angles as
// Radiance's glass.
struct Material {
  std::string name;
  double reflectance = 0;     // Lambertian reflectance in [0, 1)
  double transmittance = -1;  // straight-through transmittance in [0, 1]; < 0 = opaque
  double specular = 0;        // reflectance of the specular part (Ward lobe or mirror)
  double roughness = 0;       // the specular part's roughness (Ward's alpha); 0 = a mirror
  double through = 0;         // Lambertian transmittance
  MaterialKind kind = MaterialKind::kLambertian;
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
