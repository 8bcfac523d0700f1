#pragma once

// A scene as Radiance reads it, so that any design can be checked in Radiance directly: each
// material as a Radiance modifier of the same reflection, each triangle as a polygon, each
// sensor as a line of an rtrace/rcontrib points file.
//
// Materials: an opaque Lambertian reflectance rho is `plastic` rho rho rho with specularity 0;
// glazing (rho, straight-through transmittance tau) is `trans` with colour c = rho + tau,
// specularity 0, transmissivity tau / c and all of it specular (Radiance's trans then reflects
// c (1 - tau / c) = rho diffusely and transmits c tau / c = tau straight through). A plastic,
// metal or trans is itself with the scene's parameters (ParametersOfKind), a glass is `glass`
// of the transmissivity the tracer gives its pane (GlassPane::TransmissivityFor).
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "core/geometry/blind.h"
#include "core/geometry/scene.h"

namespace fenestra {

// Material `m` as a Radiance modifier, by the rules above: its type ("plastic", "metal",
// "trans" or "glass") and its real arguments, each grey colour three times.
struct RadianceModifier {
  const char* type = "";
  std::vector<double> reals;
};
RadianceModifier RadianceModifierOf(const Material& m);

// The modifier name of material `index` named `name`: "m<index>_" and the name with every
// character Radiance does not take in a name replaced by '_'.
std::string RadianceName(uint32_t index, const std::string& name);

// Writes the scene's materials and complete geometry at `design` (AssembleMesh) as a Radiance
// scene description; returns the number of polygons. Atomic: on failure no file is left.
absl::StatusOr<size_t> WriteSceneRad(const std::string& path, const Scene& scene,
                                     const BlindDesign& design);

// Writes the scene's sensors, one line each: position, then direction. Atomic.
absl::Status WriteScenePoints(const std::string& path, const Scene& scene);

}  // namespace fenestra
