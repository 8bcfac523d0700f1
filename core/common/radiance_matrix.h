#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"

namespace fenestra {

// Row-major dense matrix of doubles, the exchange type between stages.
using Matrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

enum class MatrixFormat { kAscii, kFloat };

// Writes `m` as a Radiance matrix (header NROWS/NCOLS/NCOMP/FORMAT), readable by rmtxop
// and dctimestep. With `components` 3 every value is written as three equal channels (a
// grey R G B, as dctimestep writes its results); otherwise `components` must be 1. Writes
// to a temporary file and renames it, so a failure never leaves a partial file at `path`.
absl::Status WriteRadianceMatrix(const std::string& path, const Matrix& m,
                                 MatrixFormat format = MatrixFormat::kAscii, int components = 1);

// The mean of B >= 2 equally shaped batch matrices and its standard error from their spread,
// entry by entry (BatchMeanAndError), in one pass over the entries.
void MeanAndError(const std::vector<Matrix>& batches, Matrix* mean, Matrix* standard_error);

// Mean of standard_error / value over the entries above `min_fraction` of their row's
// maximum (of the whole matrix's maximum when !per_row); 0 when there are none. Takes blocks
// of whole rows (topRows) without copying them.
double MeanRelativeError(Eigen::Ref<const Matrix> value, Eigen::Ref<const Matrix> standard_error,
                         double min_fraction = 0.01, bool per_row = true);

// Reads a one-component Radiance matrix (ascii, float or double), or a gzip-free
// whitespace-separated text table when the file has no Radiance header.
absl::StatusOr<Matrix> ReadRadianceMatrix(const std::string& path);

// Reads a Radiance matrix of any number of components (ascii, float or double): one matrix
// per component. A file without a Radiance header is read as a one-component text table.
absl::StatusOr<std::vector<Matrix>> ReadRadianceMatrixComponents(const std::string& path);

}  // namespace fenestra
