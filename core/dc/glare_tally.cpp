#include "core/dc/glare_tally.h"

#include <algorithm>

#include "absl/strings/str_cat.h"
#include "core/common/status_macros.h"

namespace fenestra {

absl::Status CheckGlareSteps(const GlareSteps& steps, int views, int columns) {
  if (steps.sun_factor.rows() != views || steps.sun_factor.cols() != columns ||
      static_cast<int>(steps.occupied.size()) != columns) {
    return absl::InvalidArgumentError(absl::StrCat(
        "glare: steps for ", steps.sun_factor.rows(), " views and ", steps.occupied.size(),
        " columns, E of ", views, " views and ", columns, " columns"));
  }
  if (!(steps.threshold > 0 && steps.threshold < 1)) {
    return absl::InvalidArgumentError(
        absl::StrCat("glare: a threshold of ", steps.threshold, ", not in (0, 1)"));
  }
  return absl::OkStatus();
}

absl::StatusOr<GlareCounts> CountGlare(const std::vector<Matrix>& batches,
                                       std::span<const SunEntry> sun, const GlareSteps& steps) {
  const int count = static_cast<int>(batches.size());
  if (count < 2) {
    return absl::InvalidArgumentError(absl::StrCat("glare: ", count, " batches, not 2 or more"));
  }
  const int views = static_cast<int>(batches[0].rows());
  const Eigen::Index columns = batches[0].cols();
  FENESTRA_RETURN_IF_ERROR(CheckGlareSteps(steps, views, static_cast<int>(columns)));
  Matrix sun_lux = Matrix::Zero(views, columns);
  for (const SunEntry& e : sun) {
    if (e.sensor < 0 || e.sensor >= views || e.column < 0 || e.column >= columns) {
      return absl::InvalidArgumentError("glare: a direct-sun entry out of range");
    }
    sun_lux(e.sensor, e.column) = e.lux;
  }
  Matrix total = Matrix::Zero(views, columns);
  for (const Matrix& e : batches) {
    if (e.rows() != views || e.cols() != columns) {
      return absl::InvalidArgumentError("glare: batches of E of different sizes");
    }
    total += e;
  }
  // Below this eye illuminance a step without the sun in view is no glare step
  const double eye_limit = EyeLuxAtDgp(steps.threshold);
  using Mask = Eigen::Array<bool, Eigen::Dynamic, Eigen::Dynamic>;
  Mask occupied(1, columns);
  for (Eigen::Index c = 0; c < columns; ++c) occupied(0, c) = steps.occupied[c];
  // The occupied steps without the sun at the eye, decided by Ev alone; those with it, one by one
  const Mask sunless = (sun_lux.array() == 0) && occupied.replicate(views, 1);
  std::vector<std::pair<int, Eigen::Index>> sunny;
  for (Eigen::Index c = 0; c < columns; ++c) {
    for (int v = 0; v < views; ++v) {
      if (sun_lux(v, c) > 0 && occupied(0, c)) sunny.emplace_back(v, c);
    }
  }
  GlareCounts out;
  Matrix e(views, columns);
  Mask glare(views, columns);
  for (int version = 0; version <= count; ++version) {
    const double weight = version == 0 ? 1.0 / count : 1.0 / (count - 1);
    if (version == 0) {
      e.noalias() = weight * total;
    } else {
      e.noalias() = weight * (total - batches[version - 1]);
    }
    glare = sunless && (e.array() >= eye_limit);
    for (const auto& [v, c] : sunny) {
      glare(v, c) = DgpWithSunFactor(std::max(0.0, e(v, c)) + sun_lux(v, c), sun_lux(v, c),
                                     steps.sun_factor(v, c)) >= steps.threshold;
    }
    std::vector<int64_t> per_view(views);
    for (int v = 0; v < views; ++v) per_view[v] = glare.row(v).count();
    out.view_steps.push_back(std::move(per_view));
    out.any_steps.push_back(glare.colwise().any().count());
  }
  return out;
}

}  // namespace fenestra
