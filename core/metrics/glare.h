#pragma once

// Glare at a view point from its vertical eye illuminance Ev (core/README.md, "Glare").
//
// The simplified daylight glare probability of Wienold (2009), DGPs = 6.22e-5 Ev + 0.184, holds
// where no glare source as bright as the sun's disc is in view; a view whose eye the sun's
// beam reaches is counted apart (ViewGlare::sunlit_hours), as DGPs understates its glare.
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

namespace fenestra {

inline constexpr double kDgpsSlopePerLux = 6.22e-5;
inline constexpr double kDgpsOffset = 0.184;
// Honeybee's imageless annual glare: the threshold and the share of hours below it to reach.
inline constexpr double kDefaultGlareThreshold = 0.40;
inline constexpr double kDefaultGlareAutonomyTargetPercent = 95.0;
// EN 17037: the share of the occupied hours whose DGP may exceed a class's limit [%].
inline constexpr double kEn17037ExceedancePercent = 5.0;

// DGPs from the vertical eye illuminance [lx].
inline double SimplifiedDgp(double eye_lux) { return kDgpsSlopePerLux * eye_lux + kDgpsOffset; }

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

// The glare of one view from its eye illuminance per time step [lx] (`eye_lux`), the steps'
// occupancy, and where given the sun's beam alone at the eye per step (`sun_lux`, as
// DirectSun gives it). InvalidArgument for lengths that differ, a threshold outside (0, 1) or
// an eye illuminance that is negative or not finite; no occupied step gives all zeros.
absl::StatusOr<ViewGlare> GlareOfView(std::span<const double> eye_lux,
                                      const std::vector<bool>& occupied,
                                      double threshold = kDefaultGlareThreshold,
                                      std::span<const double> sun_lux = {});

}  // namespace fenestra
