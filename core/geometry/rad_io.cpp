#include "core/geometry/rad_io.h"

#include <cctype>
#include <ostream>

#include "core/common/atomic_file.h"

namespace fenestra {
namespace {

void WriteMaterial(std::ostream& out, uint32_t index, const Material& m) {
  const std::string name = RadianceName(index, m.name);
  if (m.transmittance > 0) {
    const double c = m.reflectance + m.transmittance;
    out << "void trans " << name << "\n0\n0\n7 " << c << ' ' << c << ' ' << c << " 0 0 "
        << m.transmittance / c << " 1\n\n";
    return;
  }
  const double r = m.reflectance;
  out << "void plastic " << name << "\n0\n0\n5 " << r << ' ' << r << ' ' << r << " 0 0\n\n";
}

}  // namespace

std::string RadianceName(uint32_t index, const std::string& name) {
  std::string out(1, 'm');
  out.append(std::to_string(index));
  out.push_back('_');
  for (const char c : name) {
    const bool kept =
        std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.';
    out += kept ? c : '_';
  }
  return out;
}

absl::StatusOr<size_t> WriteSceneRad(const std::string& path, const Scene& scene,
                                     const BlindDesign& design) {
  const TriangleMesh mesh = AssembleMesh(scene, design);
  const absl::Status written = WriteFileAtomically(path, [&](std::ostream& out) {
    out << "# fenestra scene export: scene '" << scene.name << "', " << mesh.TriangleCount()
        << " triangles\n\n";
    out.precision(10);
    for (uint32_t m = 0; m < scene.materials.size(); ++m) {
      WriteMaterial(out, m, scene.materials[m]);
    }
    for (size_t t = 0; t < mesh.TriangleCount(); ++t) {
      out << RadianceName(mesh.material[t], scene.materials[mesh.material[t]].name) << " polygon t"
          << t << "\n0\n0\n9";
      for (int k = 0; k < 3; ++k) {
        const Vec3d& v = mesh.vertices[3 * t + k];
        out << ' ' << v.x << ' ' << v.y << ' ' << v.z;
      }
      out << '\n';
    }
    return absl::OkStatus();
  });
  if (!written.ok()) return written;
  return mesh.TriangleCount();
}

absl::Status WriteScenePoints(const std::string& path, const Scene& scene) {
  return WriteFileAtomically(path, [&](std::ostream& out) {
    out.precision(10);
    for (const Sensor& s : scene.sensors) {
      out << s.position.x << ' ' << s.position.y << ' ' << s.position.z << ' ' << s.direction.x
          << ' ' << s.direction.y << ' ' << s.direction.z << '\n';
    }
    return absl::OkStatus();
  });
}

}  // namespace fenestra
