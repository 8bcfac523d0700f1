#include "core/geometry/rad_io.h"

#include <cctype>
#include <initializer_list>
#include <ostream>

#include "core/common/atomic_file.h"
#include "core/geometry/material.h"
#include "core/trace/glass.h"  // header-only: the pane's formulas, shared with the tracer

namespace fenestra {
namespace {

// Writes `void <type> <name>`, no string or integer arguments, then `values` (each grey
// colour three times where the caller repeats it).
void WriteModifier(std::ostream& out, const char* type, const std::string& name,
                   std::initializer_list<double> values) {
  out << "void " << type << ' ' << name << "\n0\n0\n" << values.size();
  for (const double v : values) out << ' ' << v;
  out << "\n\n";
}

void WriteMaterial(std::ostream& out, uint32_t index, const Material& m) {
  const std::string name = RadianceName(index, m.name);
  const RadianceParameters p = ParametersOfKind(m);
  const double c = p.colour, s = p.specularity, a = p.roughness;
  switch (m.kind) {
    case MaterialKind::kLambertian:
      if (m.transmittance > 0) {
        const double g = m.reflectance + m.transmittance;
        WriteModifier(out, "trans", name, {g, g, g, 0, 0, m.transmittance / g, 1});
      } else {
        WriteModifier(out, "plastic", name, {m.reflectance, m.reflectance, m.reflectance, 0, 0});
      }
      break;
    case MaterialKind::kPlastic:
      WriteModifier(out, "plastic", name, {c, c, c, s, a});
      break;
    case MaterialKind::kMetal:
      WriteModifier(out, "metal", name, {c, c, c, s, a});
      break;
    case MaterialKind::kTrans:
      WriteModifier(out, "trans", name, {c, c, c, s, a, p.transmissivity, p.transmitted_specular});
      break;
    case MaterialKind::kGlass: {
      // The tracer's pane (ToTraceMaterial): the same transmissivity, in float
      const double t = GlassPane::TransmissivityFor(static_cast<float>(m.transmittance));
      WriteModifier(out, "glass", name, {t, t, t});
      break;
    }
  }
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
