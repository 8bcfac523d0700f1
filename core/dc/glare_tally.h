#pragma once

// The glare steps of a design's views (core/optimize/comfort.h), counted from the batches of
// E at the eyes as the annual metrics' tallies are (HourTally): per jackknife version (0: the
// mean of the batches; 1 + b: the mean without batch b), so that the glare figures get their
// standard errors. One definition of a glare step for the CPU's counts and the GPU's: an
// occupied step is one where the view's DGP (dgp_formula.h) reaches the threshold, from Ev
// alone where the sun's beam does not reach the eye, with the sun as glare source where it
// does.
#include <cstdint>
#include <span>
#include <vector>

#include "absl/status/statusor.h"
#include "core/common/radiance_matrix.h"
#include "core/dc/sun_entry.h"
#include "core/metrics/glare.h"

namespace fenestra {

// What decides a glare step, per column of the sky E is taken through.
struct GlareSteps {
  std::vector<bool> occupied;  // per column
  // Per view (a row) and column, the geometric factor of the column's sun (SunGlareFactor,
  // core/metrics/glare.h); 0 where the column has no sun or it is behind the eye
  Matrix sun_factor;
  double threshold = kDefaultGlareThreshold;  // the DGP that counts as glare, in (0, 1)
};

// Per version, per view the occupied steps in glare, and the steps in which some view is.
struct GlareCounts {
  std::vector<std::vector<int64_t>> view_steps;
  std::vector<int64_t> any_steps;
};

// InvalidArgument unless `steps` fits `views` views and `columns` columns and its threshold
// lies in (0, 1).
absl::Status CheckGlareSteps(const GlareSteps& steps, int views, int columns);

// The counts of E's batches (views x columns each, the sky's light without the sun's beam)
// with `sun` the beam at the eyes (entries by view, then column). InvalidArgument for fewer
// than 2 batches, batches or entries that do not fit `steps`.
absl::StatusOr<GlareCounts> CountGlare(const std::vector<Matrix>& batches,
                                       std::span<const SunEntry> sun, const GlareSteps& steps);

}  // namespace fenestra
