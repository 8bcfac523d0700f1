#include "core/geometry/rad_io.h"

#include <cctype>
#include <ostream>

#include "core/common/atomic_file.h"
#include "core/geometry/material.h"
#include "core/trace/glass.h"  // header-only: the pane's formulas, shared with the tracer

namespace fenestra {
namespace {

void WriteMaterial(std::ostream& out, uint32_t index, const Material& m) {
  const RadianceModifier modifier = RadianceModifierOf(m);
  out << "void " << modifier.type << ' ' << RadianceName(index, m.name) << "\n0\n0\n"
      << modifier.reals.size();
  for (const double v : modifier.reals) out << ' ' << v;
  out << "\n\n";
}

}  // namespace

RadianceModifier RadianceModifierOf(const Material& m) {
  const RadianceParameters p = ParametersOfKind(m);
  const double c = p.colour, s = p.specularity, a = p.roughness;
  switch (m.kind) {
    case MaterialKind::kLambertian:
      if (m.transmittance > 0) {
        const double g = m.reflectance + m.transmittance;
        return {"trans", {g, g, g, 0, 0, m.transmittance / g, 1}};
      }
      return {"plastic", {m.reflectance, m.reflectance, m.reflectance, 0, 0}};
    case MaterialKind::kPlastic:
      return {"plastic", {c, c, c, s, a}};
    case MaterialKind::kMetal:
      return {"metal", {c, c, c, s, a}};
    case MaterialKind::kTrans:
      return {"trans", {c, c, c, s, a, p.transmissivity, p.transmitted_specular}};
    case MaterialKind::kGlass: {
      // The tracer's pane (ToTraceMaterial): the same transmissivity, in float
      const double t = GlassPane::TransmissivityFor(static_cast<float>(m.transmittance));
      return {"glass", {t, t, t}};
    }
  }
  return {"plastic", {0, 0, 0, 0, 0}};
}

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
