#include "core/metrics/glare.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "absl/strings/str_cat.h"
#include "core/metrics/dgp_formula.h"

namespace fenestra {

// The largest position index (evalglare's)
constexpr double kMaxPositionIndex = 16;

double Dgp(double eye_lux, std::span<const GlareSource> sources) {
  double sum = 0;
  for (const GlareSource& s : sources) {
    sum += s.luminance * s.luminance * s.solid_angle / (s.position_index * s.position_index);
  }
  return DgpOfSum(eye_lux, sum);
}

double EyeLuxAtDgp(double dgp) { return (dgp - kDgpOffset) / kDgpEvSlope; }

double PositionIndex(Vec3d view, Vec3d up, Vec3d to_source) {
  constexpr double kDegrees = 180 / std::numbers::pi;
  const Vec3d v = Normalize(view), d = Normalize(to_source);
  const Vec3d u = Normalize(up - Dot(up, v) * v);  // up, square to the view
  const double cos_sigma = std::clamp(Dot(v, d), -1.0, 1.0);
  const double sigma = std::acos(cos_sigma) * kDegrees;  // from the line of sight
  // tau: from up to the source's direction about the line of sight
  const Vec3d across = d - cos_sigma * v;
  const double across_length = Length(across);
  const double tau =
      across_length > 0
          ? std::acos(std::clamp(Dot(u, across) / across_length, -1.0, 1.0)) * kDegrees
          : 0.0;
  double p;
  if (Dot(u, d) < 0) {
    // Below the line of sight (Iwata; CIE 2010)
    const double c = std::cos(tau / kDegrees);
    const double beta =
        std::atan(std::tan(sigma / kDegrees) * std::sqrt(1 + 0.3225 * c * c)) * kDegrees;
    p = std::exp(6.49e-3 * beta + 21.0e-5 * beta * beta);
  } else {
    // Guth, as the IES handbook gives it
    p = std::exp((35.2 - 0.31889 * tau - 1.22 * std::exp(-2 * tau / 9)) * 1e-3 * sigma +
                 (21 + 0.26667 * tau - 0.002963 * tau * tau) * 1e-5 * sigma * sigma);
  }
  return std::min(p, kMaxPositionIndex);
}

double DgpWithSun(double eye_lux, double sun_eye_lux, Vec3d view, Vec3d up, Vec3d to_sun) {
  return DgpWithSunFactor(eye_lux, sun_eye_lux, SunGlareFactor(view, up, to_sun));
}

double SunGlareFactor(Vec3d view, Vec3d up, Vec3d to_sun) {
  const double cos_view = Dot(Normalize(view), Normalize(to_sun));
  if (!(cos_view > 0)) return 0;
  // The beam's normal illuminance at the eye spread over the disc: L = E_sun / (cos omega)
  const double p = PositionIndex(view, up, to_sun);
  return 1 / (cos_view * cos_view * kSunSolidAngleSr * p * p);
}

GlareClass ClassOfDgp(double dgp) {
  if (dgp < 0.35) return GlareClass::kImperceptible;
  if (dgp < 0.40) return GlareClass::kPerceptible;
  if (dgp < 0.45) return GlareClass::kDisturbing;
  return GlareClass::kIntolerable;
}

std::string_view GlareClassName(GlareClass c) {
  switch (c) {
    case GlareClass::kImperceptible:
      return "imperceptible";
    case GlareClass::kPerceptible:
      return "perceptible";
    case GlareClass::kDisturbing:
      return "disturbing";
    case GlareClass::kIntolerable:
      return "intolerable";
  }
  return "?";
}

std::string_view En17037GlareName(En17037Glare c) {
  switch (c) {
    case En17037Glare::kHigh:
      return "high";
    case En17037Glare::kMedium:
      return "medium";
    case En17037Glare::kMinimum:
      return "minimum";
    case En17037Glare::kNone:
      return "none";
  }
  return "?";
}

absl::StatusOr<ViewGlare> GlareOfView(std::span<const double> dgp,
                                      const std::vector<bool>& occupied, double threshold,
                                      const std::vector<bool>& sunlit) {
  if (occupied.size() != dgp.size() || (!sunlit.empty() && sunlit.size() != dgp.size())) {
    return absl::InvalidArgumentError(absl::StrCat("glare: ", dgp.size(), " DGP values, ",
                                                   occupied.size(), " occupancy flags and ",
                                                   sunlit.size(), " sun flags"));
  }
  if (!(threshold > 0 && threshold < 1)) {
    return absl::InvalidArgumentError(
        absl::StrCat("glare: the DGP threshold must lie in (0, 1), got ", threshold));
  }
  ViewGlare g;
  std::vector<double> values;
  int below = 0;
  for (size_t i = 0; i < dgp.size(); ++i) {
    if (!(dgp[i] >= 0 && dgp[i] <= 1)) {
      return absl::InvalidArgumentError(absl::StrCat("glare: DGP ", dgp[i], " at step ", i));
    }
    if (!occupied[i]) continue;
    values.push_back(dgp[i]);
    below += dgp[i] < threshold ? 1 : 0;
    ++g.class_hours[static_cast<int>(ClassOfDgp(dgp[i]))];
    g.sunlit_hours += !sunlit.empty() && sunlit[i] ? 1 : 0;
  }
  g.occupied_hours = static_cast<int>(values.size());
  if (values.empty()) return g;
  double sum = 0;
  for (const double d : values) sum += d;
  g.mean_dgp = sum / static_cast<double>(values.size());
  g.autonomy_percent = 100.0 * below / static_cast<double>(values.size());
  // The largest DGP left once the brightest 5% of the hours are set aside
  std::sort(values.begin(), values.end());
  const size_t allowed = static_cast<size_t>(
      std::floor(kEn17037ExceedancePercent / 100.0 * static_cast<double>(values.size())));
  g.dgp_95 = values[values.size() - 1 - allowed];
  g.en17037 = g.dgp_95 <= 0.35   ? En17037Glare::kHigh
              : g.dgp_95 <= 0.40 ? En17037Glare::kMedium
              : g.dgp_95 <= 0.45 ? En17037Glare::kMinimum
                                 : En17037Glare::kNone;
  return g;
}

}  // namespace fenestra
