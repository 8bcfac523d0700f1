#pragma once

#include <Eigen/Core>
#include <string>

#include "absl/status/status.h"
#include "absl/status/statusor.h"

namespace fenestra {

// Row-major dense matrix of doubles, the exchange type between stages.
using Matrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

enum class MatrixFormat { kAscii, kFloat };

// Writes `m` as a one-component Radiance matrix (header NROWS/NCOLS/NCOMP=1/FORMAT),
// readable by rmtxop and dctimestep. Writes to a temporary file and renames it, so a
// failure never leaves a partial file at `path`.
absl::Status WriteRadianceMatrix(const std::string& path, const Matrix& m,
                                 MatrixFormat format = MatrixFormat::kAscii);

// Reads a one-component Radiance matrix (ascii, float or double), or a gzip-free
// whitespace-separated text table when the file has no Radiance header.
absl::StatusOr<Matrix> ReadRadianceMatrix(const std::string& path);

}  // namespace fenestra
