#include "core/metrics/illuminance.h"

#include <cstdint>
#include <string>

#include "absl/strings/str_cat.h"

namespace fenestra {

std::vector<int> LitColumns(const Matrix& sky) {
  // Row by row, as the matrix lies in memory (a column's entries are a row apart)
  std::vector<uint8_t> lit(static_cast<size_t>(sky.cols()), 0);
  for (Eigen::Index i = 0; i < sky.rows(); ++i) {
    for (Eigen::Index j = 0; j < sky.cols(); ++j) lit[j] |= sky(i, j) != 0.0;
  }
  std::vector<int> columns;
  for (Eigen::Index j = 0; j < sky.cols(); ++j) {
    if (lit[j]) columns.push_back(static_cast<int>(j));
  }
  return columns;
}

absl::Status CheckColumns(std::span<const int> columns, int steps) {
  for (size_t c = 0; c < columns.size(); ++c) {
    if (columns[c] < 0 || columns[c] >= steps) {
      return absl::InvalidArgumentError(
          absl::StrCat("column ", c, " is time step ", columns[c], ", outside [0, ", steps, ")"));
    }
    if (c > 0 && columns[c] <= columns[c - 1]) {
      return absl::InvalidArgumentError(absl::StrCat("columns must be strictly ascending: entry ",
                                                     c, " (", columns[c], ") follows ",
                                                     columns[c - 1]));
    }
  }
  return absl::OkStatus();
}

absl::StatusOr<Matrix> Illuminance(const Matrix& dc, const Matrix& sky,
                                   std::span<const int> columns) {
  return Illuminance(std::span<const Matrix>(&dc, 1), std::span<const Matrix>(&sky, 1), columns);
}

absl::StatusOr<Matrix> Illuminance(std::span<const Matrix> dc_channels,
                                   std::span<const Matrix> sky_channels,
                                   std::span<const int> columns) {
  const size_t nd = dc_channels.size();
  const size_t ns = sky_channels.size();
  if ((nd != 1 && nd != 3) || (ns != 1 && ns != 3)) {
    return absl::InvalidArgumentError(absl::StrCat(
        "need 1 or 3 channels of daylight coefficients and of sky, got ", nd, " and ", ns));
  }
  const Matrix& dc0 = dc_channels[0];
  const Matrix& sky0 = sky_channels[0];
  for (const Matrix& d : dc_channels) {
    if (d.rows() != dc0.rows() || d.cols() != dc0.cols()) {
      return absl::InvalidArgumentError("daylight coefficient channels differ in shape");
    }
  }
  for (const Matrix& s : sky_channels) {
    if (s.rows() != sky0.rows() || s.cols() != sky0.cols()) {
      return absl::InvalidArgumentError("sky channels differ in shape");
    }
  }
  if (dc0.cols() != sky0.rows()) {
    return absl::InvalidArgumentError(absl::StrCat("daylight coefficients have ", dc0.cols(),
                                                   " patches, the sky has ", sky0.rows(), " rows"));
  }
  const absl::Status columns_ok = CheckColumns(columns, static_cast<int>(sky0.cols()));
  if (!columns_ok.ok()) return columns_ok;

  const std::vector<int> index(columns.begin(), columns.end());
  auto weight = [&](size_t c) { return (nd == 1 && ns == 1) ? 1.0 : kRgbBrightnessWeights[c]; };

  // Grey coefficients: weight the sky channels first, then one product
  if (nd == 1) {
    Matrix sky_grey = weight(0) * sky0(Eigen::all, index);
    for (size_t c = 1; c < ns; ++c) sky_grey += weight(c) * sky_channels[c](Eigen::all, index);
    Matrix e = kWhiteEfficacyLumensPerWatt * (dc0 * sky_grey);
    return e;
  }

  // Coloured coefficients: one product per channel
  Matrix e = Matrix::Zero(dc0.rows(), static_cast<Eigen::Index>(index.size()));
  for (size_t c = 0; c < 3; ++c) {
    const Matrix& s = sky_channels[ns == 1 ? 0 : c];
    e.noalias() +=
        (kWhiteEfficacyLumensPerWatt * weight(c)) * (dc_channels[c] * s(Eigen::all, index));
  }
  return e;
}

}  // namespace fenestra
