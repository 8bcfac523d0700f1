#pragma once

// Glare at a view point from its vertical eye illuminance Ev (core/README.md, "Glare").
//
// - The simplified daylight glare probability (Wienold 2009), DGPs = 6.22e-5 Ev + 0.184: Ev
//   alone, which holds where no glare source as bright as the sun's disc is in view.
// - The daylight glare probability (Wienold & Christoffersen 2006) with the sun as its glare
//   source, as the enhanced simplified DGP takes it: DGP = 5.87e-5 Ev + 0.092 log10(1 +
//   sum L^2 w / (Ev^1.87 P^2)) + 0.159, at most 1, with evalglare's constants and without its
//   low-light correction (off unless asked for, -C l+); the sun's luminance L is the normal
//   illuminance of its beam through glazing and blind over its disc's solid angle w, P its
//   position index after Guth (above the line of sight) or Iwata (below), as evalglare
//   computes them. Without the sun in view it is 5.87e-5 Ev + 0.159.
// Comfort classes: DGP < 0.35 imperceptible, < 0.40 perceptible, < 0.45 disturbing, else
// intolerable. Annual figures over the occupied hours: the glare autonomy (share of hours
// below a threshold, 0.40 as Honeybee's imageless annual glare; its target 95%) and the
// EN 17037 glare protection class (the DGP exceeded in no more than 5% of the hours: at most
// 0.35 high, 0.40 medium, 0.45 minimum).
#include <array>
#include <span>
#include <string_view>
#include <vector>

#include "absl/status/statusor.h"
#include "core/common/vec3.h"
#include "core/metrics/dgp_formula.h"

namespace fenestra {

inline constexpr double kDgpsSlopePerLux = 6.22e-5;
inline constexpr double kDgpsOffset = 0.184;
// The solid angle of the sun's disc, 0.533 degrees across [sr].
inline constexpr double kSunSolidAngleSr = 6.805e-5;
// Honeybee's imageless annual glare: the threshold and the share of hours below it to reach.
inline constexpr double kDefaultGlareThreshold = 0.40;
inline constexpr double kDefaultGlareAutonomyTargetPercent = 95.0;
// EN 17037: the share of the occupied hours whose DGP may exceed a class's limit [%].
inline constexpr double kEn17037ExceedancePercent = 5.0;

// DGPs from the vertical eye illuminance [lx].
inline double SimplifiedDgp(double eye_lux) { return kDgpsSlopePerLux * eye_lux + kDgpsOffset; }

// A glare source: its mean luminance [cd/m2], solid angle [sr] and position index.
struct GlareSource {
  double luminance = 0;
  double solid_angle = 0;
  double position_index = 1;
};

// The DGP at vertical eye illuminance `eye_lux` (> 0) with `sources`.
double Dgp(double eye_lux, std::span<const GlareSource> sources);

// The eye illuminance at which the DGP without a glare source is `dgp` [lx] (negative below
// the DGP of darkness): with no source in view, DGP >= dgp exactly when Ev >= this.
double EyeLuxAtDgp(double dgp);

// The position index of a source in direction `to_source` from an eye looking along `view`
// with `up` (unit vectors; up not along view): Guth's above the line of sight, Iwata's below,
// at most 16.
double PositionIndex(Vec3d view, Vec3d up, Vec3d to_source);

// The DGP with the sun as glare source: the sun in direction `to_sun` whose beam, through
// whatever lies between, gives the eye plane (facing `view`) `sun_eye_lux` of the eye's
// `eye_lux`. Without the beam (sun_eye_lux 0) the DGP of Ev alone.
double DgpWithSun(double eye_lux, double sun_eye_lux, Vec3d view, Vec3d up, Vec3d to_sun);
// The same in two steps, for many illuminances of one view and sun: the part of the sun's
// term that depends on the geometry alone, 1 / (cos^2 omega P^2) (L^2 omega / P^2 is
// sun_eye_lux^2 times it; 0 where the sun is not in front of the eye), then the DGP from it
// (DgpWithSunFactor, dgp_formula.h).
double SunGlareFactor(Vec3d view, Vec3d up, Vec3d to_sun);

enum class GlareClass { kImperceptible, kPerceptible, kDisturbing, kIntolerable };
GlareClass ClassOfDgp(double dgp);
std::string_view GlareClassName(GlareClass c);

enum class En17037Glare { kHigh, kMedium, kMinimum, kNone };
std::string_view En17037GlareName(En17037Glare c);

// A view's annual glare over the occupied hours.
struct ViewGlare {
  int occupied_hours = 0;
  double mean_dgp = 0;
  double autonomy_percent = 0;  // hours with DGP below the threshold
  double dgp_95 = 0;            // exceeded in at most kEn17037ExceedancePercent of the hours
  En17037Glare en17037 = En17037Glare::kNone;
  std::array<int, 4> class_hours{};  // per GlareClass
  int sunlit_hours = 0;              // hours the sun's beam reaches the eye
};

// The glare of one view from its DGP per time step (`dgp`), the steps' occupancy and, where
// given, whether the sun's beam reaches the eye per step (`sunlit`). InvalidArgument for
// lengths that differ, a threshold outside (0, 1) or a DGP outside [0, 1]; no occupied step
// gives all zeros.
absl::StatusOr<ViewGlare> GlareOfView(std::span<const double> dgp,
                                      const std::vector<bool>& occupied,
                                      double threshold = kDefaultGlareThreshold,
                                      const std::vector<bool>& sunlit = {});

}  // namespace fenestra
