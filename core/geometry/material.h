#pragma once

// Radiance's grey materials (scene.proto's Material.Plastic, Metal, Trans and Glass) as the
// parts of mesh.h's Material and back, and the rules the parts of every material keep.
#include <string>

#include "absl/status/status.h"
#include "core/geometry/mesh.h"

namespace fenestra {

// Highest transmittance of a glass at normal incidence: a bare pane of index 1.52 transmits
// 0.916 (its surfaces' reflection alone).
inline constexpr double kMaxGlassNormalTransmittance = 0.9;

// Radiance's arguments of a grey plastic, metal or trans: colour c, specularity s, the lobe's
// roughness, and for trans the transmissivity T and the transmitted specular T_s.
struct RadianceParameters {
  double colour = 0, specularity = 0, roughness = 0, transmissivity = 0, transmitted_specular = 0;
};

// The parts of a plastic, metal or trans (`kind`) of parameters `p`, as mesh.h's comment gives
// them; the name is left empty.
Material MaterialOfKind(MaterialKind kind, const RadianceParameters& p);

// The parameters of a plastic, metal or trans `m`: ones of which MaterialOfKind gives m's parts
// back bit for bit where there are such (every material it made), else the nearest. A
// parameter the parts leave open is 0 (T_s of a trans that transmits nothing).
RadianceParameters ParametersOfKind(const Material& m);

// Whether the tracer takes the parts of `m` (ToTraceMaterial in core/trace/trace_geometry.h
// applies these rules): InvalidArgument "<rule>, got <value>" for a part outside [0, 1],
// reflectance or reflectance + specular at 1 or above (a closed room would never lose light),
// parts summing above 1, or a glass that no pane of index 1.52 can be.
absl::Status CheckMaterialParts(const Material& m);

// One line for people: "reflectance 0.5", "reflectance 0.1, transmittance 0.6", "metal:
// colour 0.8, specularity 0.9, roughness 0.05", "glass: transmittance 0.88 at normal
// incidence".
std::string DescribeMaterial(const Material& m);

}  // namespace fenestra
