#include "core/geometry/material.h"

#include <algorithm>
#include <bit>
#include <cstdint>

#include "absl/strings/str_cat.h"

namespace fenestra {
namespace {

// How far ParametersOfKind looks, in units in the last place of each free parameter, for
// parameters that give the parts exactly: the quotients it starts from lie within 4 of them.
constexpr int kSearchUlps = 6;

bool SameParts(const Material& a, const Material& b) {
  return a.reflectance == b.reflectance && a.transmittance == b.transmittance &&
         a.specular == b.specular && a.roughness == b.roughness && a.through == b.through;
}

// `x` >= 0 moved by `ulps` representable doubles; false below 0. A -0 counts as 0 (its sign
// bit would make its bits the least int64_t).
bool Step(double x, int ulps, double* out) {
  const int64_t bits = std::bit_cast<int64_t>(x + 0.0) + ulps;
  if (bits < 0) return false;
  *out = std::bit_cast<double>(bits);
  return true;
}

// The parameters near `estimate`, moving only `free` (the rest follow from the parts exactly),
// of which MaterialOfKind gives `m`'s parts; `estimate` where none does.
RadianceParameters Refine(const Material& m, const RadianceParameters& estimate,
                          std::initializer_list<double RadianceParameters::*> free) {
  const int n = static_cast<int>(free.size());
  const int side = 2 * kSearchUlps + 1;
  int combinations = 1;
  for (int i = 0; i < n; ++i) combinations *= side;
  for (int c = 0; c < combinations; ++c) {
    RadianceParameters p = estimate;
    bool valid = true;
    int rest = c;
    for (double RadianceParameters::*member : free) {
      // Offsets 0, -1, 1, -2, 2, ...: the estimate first
      const int digit = rest % side;
      rest /= side;
      const int offset = (digit + 1) / 2 * (digit % 2 == 1 ? -1 : 1);
      valid = valid && Step(estimate.*member, offset, &(p.*member));
    }
    if (valid && SameParts(MaterialOfKind(m.kind, p), m)) return p;
  }
  return estimate;
}

double Ratio(double part, double whole) { return whole > 0 ? part / whole : 0; }

}  // namespace

Material MaterialOfKind(MaterialKind kind, const RadianceParameters& p) {
  Material m;
  m.kind = kind;
  m.roughness = p.roughness;
  const double diffuse = p.colour * (1 - p.specularity);
  switch (kind) {
    case MaterialKind::kPlastic:
      m.reflectance = diffuse;
      m.specular = p.specularity;
      break;
    case MaterialKind::kMetal:
      m.reflectance = diffuse;
      m.specular = p.colour * p.specularity;
      break;
    case MaterialKind::kTrans: {
      const double transmitted = diffuse * p.transmissivity;
      m.reflectance = diffuse * (1 - p.transmissivity);
      m.specular = p.specularity;
      m.through = transmitted * (1 - p.transmitted_specular);
      m.transmittance = transmitted * p.transmitted_specular;
      break;
    }
    default:
      break;
  }
  return m;
}

RadianceParameters ParametersOfKind(const Material& m) {
  using P = RadianceParameters;
  P p;
  p.roughness = m.roughness;
  switch (m.kind) {
    case MaterialKind::kPlastic:
      p.specularity = m.specular;
      p.colour = Ratio(m.reflectance, 1 - m.specular);
      return Refine(m, p, {&P::colour});
    case MaterialKind::kMetal:
      p.colour = m.reflectance + m.specular;
      p.specularity = Ratio(m.specular, p.colour);
      return Refine(m, p, {&P::colour, &P::specularity});
    case MaterialKind::kTrans: {
      const double straight = std::max(m.transmittance, 0.0);
      const double transmitted = m.through + straight;
      const double diffuse = m.reflectance + transmitted;
      p.specularity = m.specular;
      p.colour = Ratio(diffuse, 1 - m.specular);
      p.transmissivity = Ratio(transmitted, diffuse);
      p.transmitted_specular = Ratio(straight, transmitted);
      return Refine(m, p, {&P::colour, &P::transmissivity, &P::transmitted_specular});
    }
    default:
      return p;
  }
}

absl::Status CheckMaterialParts(const Material& m) {
  const double rho = m.reflectance, tau = std::max(m.transmittance, 0.0);
  const double specular = m.specular, through = m.through;
  const auto error = [](const char* rule, double value) {
    return absl::InvalidArgumentError(absl::StrCat(rule, ", got ", value));
  };
  if (!(rho >= 0 && rho < 1)) return error("reflectance must be in [0, 1)", rho);
  if (!(specular >= 0 && specular < 1)) return error("specular must be in [0, 1)", specular);
  if (!(m.roughness >= 0 && m.roughness <= 1)) {
    return error("roughness must be in [0, 1]", m.roughness);
  }
  if (!(through >= 0 && through <= 1)) return error("through must be in [0, 1]", through);
  if (!(m.transmittance <= 1)) return error("transmittance above 1", tau);
  if (!(rho + specular < 1)) return error("reflectance + specular must be below 1", rho + specular);
  if (!(rho + specular + tau + through <= 1)) {
    return error("transmittance must be at most 1 - reflectance", rho + specular + tau + through);
  }
  if (m.kind == MaterialKind::kGlass && !(rho == 0 && specular == 0 && through == 0 && tau > 0 &&
                                          tau <= kMaxGlassNormalTransmittance)) {
    return error("glass transmits at normal incidence in (0, 0.9]", tau);
  }
  return absl::OkStatus();
}

std::string DescribeMaterial(const Material& m) {
  if (m.kind == MaterialKind::kGlass) {
    return absl::StrCat("glass: transmittance ", m.transmittance, " at normal incidence");
  }
  if (m.kind == MaterialKind::kLambertian) {
    if (m.transmittance < 0) return absl::StrCat("reflectance ", m.reflectance);
    return absl::StrCat("reflectance ", m.reflectance, ", transmittance ", m.transmittance);
  }
  const RadianceParameters p = ParametersOfKind(m);
  const char* kind = m.kind == MaterialKind::kPlastic ? "plastic"
                     : m.kind == MaterialKind::kMetal ? "metal"
                                                      : "trans";
  std::string out = absl::StrCat(kind, ": colour ", p.colour, ", specularity ", p.specularity,
                                 ", roughness ", p.roughness);
  if (m.kind == MaterialKind::kTrans) {
    absl::StrAppend(&out, ", transmissivity ", p.transmissivity, ", transmitted specular ",
                    p.transmitted_specular);
  }
  return out;
}

}  // namespace fenestra
