#include "core/metrics/glare.h"

#include <algorithm>
#include <cmath>

#include "absl/strings/str_cat.h"

namespace fenestra {

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

absl::StatusOr<ViewGlare> GlareOfView(std::span<const double> eye_lux,
                                      const std::vector<bool>& occupied, double threshold,
                                      std::span<const double> sun_lux) {
  if (occupied.size() != eye_lux.size() || (!sun_lux.empty() && sun_lux.size() != eye_lux.size())) {
    return absl::InvalidArgumentError(absl::StrCat("glare: ", eye_lux.size(), " eye illuminances, ",
                                                   occupied.size(), " occupancy flags and ",
                                                   sun_lux.size(), " sun illuminances"));
  }
  if (!(threshold > 0 && threshold < 1)) {
    return absl::InvalidArgumentError(
        absl::StrCat("glare: the DGP threshold must lie in (0, 1), got ", threshold));
  }
  ViewGlare g;
  std::vector<double> dgp;
  int below = 0;
  for (size_t i = 0; i < eye_lux.size(); ++i) {
    if (!(std::isfinite(eye_lux[i]) && eye_lux[i] >= 0)) {
      return absl::InvalidArgumentError(
          absl::StrCat("glare: eye illuminance ", eye_lux[i], " lx at step ", i));
    }
    if (!occupied[i]) continue;
    const double d = SimplifiedDgp(eye_lux[i]);
    dgp.push_back(d);
    below += d < threshold ? 1 : 0;
    ++g.class_hours[static_cast<int>(ClassOfDgp(d))];
    g.sunlit_hours += !sun_lux.empty() && sun_lux[i] > 0 ? 1 : 0;
  }
  g.occupied_hours = static_cast<int>(dgp.size());
  if (dgp.empty()) return g;
  double sum = 0;
  for (const double d : dgp) sum += d;
  g.mean_dgp = sum / static_cast<double>(dgp.size());
  g.autonomy_percent = 100.0 * below / static_cast<double>(dgp.size());
  // The largest DGP left once the brightest 5% of the hours are set aside
  std::sort(dgp.begin(), dgp.end());
  const size_t allowed = static_cast<size_t>(
      std::floor(kEn17037ExceedancePercent / 100.0 * static_cast<double>(dgp.size())));
  g.dgp_95 = dgp[dgp.size() - 1 - allowed];
  g.en17037 = g.dgp_95 <= 0.35   ? En17037Glare::kHigh
              : g.dgp_95 <= 0.40 ? En17037Glare::kMedium
              : g.dgp_95 <= 0.45 ? En17037Glare::kMinimum
                                 : En17037Glare::kNone;
  return g;
}

}  // namespace fenestra
