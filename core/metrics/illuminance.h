// Illuminance from daylight coefficients and a sky matrix: E = 179 lm/W x D . S, with
// Radiance's constants (WHTEFFICACY in src/common/color.h, and the CIE_rf/gf/bf weights of
// its default RGB primaries for 3-channel data).
//
// Only the chosen time steps (columns of S) are computed, normally the daytime ones: a night
// column of S is all zero, so its illuminance is zero and nothing needs to be multiplied.
// The result keeps only the chosen columns, in the given order: column c of the result is
// time step columns[c]. The annual metrics (annual_metrics.h) take the same column list
// and count every time step not in it as E = 0.
#pragma once

#include <array>
#include <span>
#include <vector>

#include "absl/status/statusor.h"
#include "core/common/radiance_matrix.h"

namespace fenestra {

// Luminous efficacy of equal-energy white over the visible band [lm/W].
inline constexpr double kWhiteEfficacyLumensPerWatt = 179.0;

// Brightness weights of R, G, B (Radiance's default primaries, equal-energy white).
inline constexpr std::array<double, 3> kRgbBrightnessWeights = {0.265074126, 0.670114631,
                                                                0.064811243};

// Indices of the columns of `sky` with at least one non-zero entry, ascending.
std::vector<int> LitColumns(const Matrix& sky);

// OK when `columns` are strictly ascending indices in [0, steps); otherwise InvalidArgument
// naming the first bad entry.
absl::Status CheckColumns(std::span<const int> columns, int steps);

// Illuminance [lx] at the time steps `columns` (strictly ascending indices into the columns
// of `sky`) of n sensors with grey daylight coefficients `dc` (n x m, sr) under the grey sky
// `sky` (m x h, W sr-1 m-2). Returns n x columns.size(). InvalidArgument when the shapes do
// not agree or a column is out of range or out of order.
absl::StatusOr<Matrix> Illuminance(const Matrix& dc, const Matrix& sky,
                                   std::span<const int> columns);

// As above with 1 (grey) or 3 (R, G, B) channels each for the coefficients and the sky:
// E = 179 x sum_c w_c D_c S_c, where a grey side is used for every channel and w are
// kRgbBrightnessWeights (weight 1 when both sides are grey).
absl::StatusOr<Matrix> Illuminance(std::span<const Matrix> dc_channels,
                                   std::span<const Matrix> sky_channels,
                                   std::span<const int> columns);

}  // namespace fenestra
