#include "core/common/radiance_matrix.h"

#include <cstring>
#include <fstream>
#include <sstream>
#include <vector>

#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/strip.h"
#include "core/common/atomic_file.h"
#include "core/common/batch_mean.h"

namespace fenestra {

absl::Status WriteRadianceMatrix(const std::string& path, const Matrix& m, MatrixFormat format,
                                 int components) {
  if (components != 1 && components != 3) {
    return absl::InvalidArgumentError(
        absl::StrCat("a Radiance matrix has 1 or 3 components here, not ", components));
  }
  const bool binary = format == MatrixFormat::kFloat;
  return WriteFileAtomically(
      path,
      [&](std::ostream& out) {
        out << "#?RADIANCE\n"
            << "NROWS=" << m.rows() << "\nNCOLS=" << m.cols() << "\nNCOMP=" << components << "\n"
            << "FORMAT=" << (binary ? "float" : "ascii") << "\n\n";
        if (binary) {
          for (Eigen::Index r = 0; r < m.rows(); ++r) {
            for (Eigen::Index c = 0; c < m.cols(); ++c) {
              const float v = static_cast<float>(m(r, c));
              for (int k = 0; k < components; ++k) {
                out.write(reinterpret_cast<const char*>(&v), sizeof v);
              }
            }
          }
        } else {
          out.precision(9);
          for (Eigen::Index r = 0; r < m.rows(); ++r) {
            for (Eigen::Index c = 0; c < m.cols(); ++c) {
              out << (c ? "\t" : "") << m(r, c);
              for (int k = 1; k < components; ++k) out << ' ' << m(r, c);
            }
            out << '\n';
          }
        }
        return absl::OkStatus();
      },
      binary);
}

double MeanRelativeError(Eigen::Ref<const Matrix> value, Eigen::Ref<const Matrix> standard_error,
                         double min_fraction, bool per_row) {
  if (value.size() == 0 || standard_error.rows() != value.rows() ||
      standard_error.cols() != value.cols()) {
    return 0;
  }
  const double matrix_max = value.maxCoeff();
  double total = 0;
  int64_t count = 0;
  for (Eigen::Index i = 0; i < value.rows(); ++i) {
    const double threshold = min_fraction * (per_row ? value.row(i).maxCoeff() : matrix_max);
    for (Eigen::Index j = 0; j < value.cols(); ++j) {
      if (value(i, j) > 0 && value(i, j) > threshold) {
        total += standard_error(i, j) / value(i, j);
        ++count;
      }
    }
  }
  return count > 0 ? total / static_cast<double>(count) : 0.0;
}

namespace {

absl::StatusOr<Matrix> ParseTable(const std::string& path, std::istream& in, long rows, long cols) {
  std::vector<double> values;
  long row_count = 0;
  long col_count = -1;
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    std::string field;
    long n = 0;
    while (fields >> field) {
      double v;
      if (!absl::SimpleAtod(field, &v)) {
        return absl::InvalidArgumentError(absl::StrCat(path, ": not a number: '", field, "'"));
      }
      values.push_back(v);
      ++n;
    }
    if (n == 0) continue;
    if (rows < 0) {
      if (col_count >= 0 && n != col_count) {
        return absl::InvalidArgumentError(absl::StrCat(path, ": row ", row_count + 1, " has ", n,
                                                       " values, expected ", col_count));
      }
      col_count = n;
      ++row_count;
    }
  }
  if (rows < 0) {
    rows = row_count;
    cols = std::max(col_count, 0L);
  }
  if (static_cast<long>(values.size()) != rows * cols) {
    return absl::InvalidArgumentError(
        absl::StrCat(path, ": expected ", rows * cols, " values, found ", values.size()));
  }
  return Matrix(Eigen::Map<Matrix>(values.data(), rows, cols));
}

}  // namespace

namespace {

// Component k of a matrix whose rows hold the components of each column in turn.
std::vector<Matrix> SplitComponents(const Matrix& interleaved, long components) {
  std::vector<Matrix> out;
  const Eigen::Index cols = interleaved.cols() / components;
  for (long k = 0; k < components; ++k) {
    Matrix m(interleaved.rows(), cols);
    for (Eigen::Index c = 0; c < cols; ++c) m.col(c) = interleaved.col(c * components + k);
    out.push_back(std::move(m));
  }
  return out;
}

absl::StatusOr<Matrix> ReadBinary(const std::string& path, std::istream& in, long rows, long cols,
                                  bool is_float) {
  Matrix m(rows, cols);
  for (long i = 0; i < rows * cols; ++i) {
    double v;
    if (is_float) {
      float f;
      in.read(reinterpret_cast<char*>(&f), sizeof f);
      v = f;
    } else {
      in.read(reinterpret_cast<char*>(&v), sizeof v);
    }
    if (!in) return absl::InvalidArgumentError(absl::StrCat(path, ": truncated data"));
    m.data()[i] = v;
  }
  return m;
}

}  // namespace

absl::StatusOr<std::vector<Matrix>> ReadRadianceMatrixComponents(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return absl::NotFoundError(absl::StrCat(path, ": cannot open"));
  const int first = in.peek();
  if (first != '#') {
    absl::StatusOr<Matrix> table = ParseTable(path, in, -1, -1);
    if (!table.ok()) return table.status();
    return std::vector<Matrix>{*std::move(table)};
  }

  long rows = -1, cols = -1, comps = 1;
  std::string format = "ascii";
  std::string line;
  while (std::getline(in, line) && !line.empty()) {
    absl::string_view v = line;
    if (absl::ConsumePrefix(&v, "NROWS=")) {
      if (!absl::SimpleAtoi(v, &rows)) rows = -1;
    } else if (absl::ConsumePrefix(&v, "NCOLS=")) {
      if (!absl::SimpleAtoi(v, &cols)) cols = -1;
    } else if (absl::ConsumePrefix(&v, "NCOMP=")) {
      if (!absl::SimpleAtoi(v, &comps)) comps = -1;
    } else if (absl::ConsumePrefix(&v, "FORMAT=")) {
      format = std::string(v);
    }
  }
  if (rows <= 0 || cols <= 0) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": header lacks NROWS/NCOLS"));
  }
  if (comps < 1 || comps > 16) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": bad NCOMP=", comps));
  }
  if (format != "ascii" && format != "float" && format != "double") {
    return absl::InvalidArgumentError(absl::StrCat(path, ": unsupported FORMAT=", format));
  }
  // The header's size against the data that follows, before anything is allocated: a value
  // takes 4 bytes as float, 8 as double, at least 1 as text
  std::streamoff data_bytes = 0;
  if (in) {
    const std::streamoff data_start = in.tellg();
    in.seekg(0, std::ios::end);
    data_bytes = in.tellg() - data_start;
    in.seekg(data_start);
  }
  const long value_bytes = format == "float" ? 4 : format == "double" ? 8 : 1;
  if (rows > data_bytes / value_bytes / cols / comps) {
    return absl::InvalidArgumentError(
        absl::StrCat(path, ": the header says NROWS=", rows, " NCOLS=", cols, " NCOMP=", comps,
                     " but only ", data_bytes, " bytes of ", format, " data follow"));
  }
  absl::StatusOr<Matrix> interleaved =
      format == "ascii" ? ParseTable(path, in, rows, cols * comps)
                        : ReadBinary(path, in, rows, cols * comps, format == "float");
  if (!interleaved.ok()) return interleaved.status();
  return SplitComponents(*interleaved, comps);
}

absl::StatusOr<Matrix> ReadRadianceMatrix(const std::string& path) {
  absl::StatusOr<std::vector<Matrix>> components = ReadRadianceMatrixComponents(path);
  if (!components.ok()) return components.status();
  if (components->size() != 1) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": NCOMP=", components->size(),
                                                   " (only one-component matrices are supported)"));
  }
  return std::move(components->front());
}

void MeanAndError(const std::vector<Matrix>& batches, Matrix* mean, Matrix* standard_error) {
  mean->resize(batches[0].rows(), batches[0].cols());
  standard_error->resize(mean->rows(), mean->cols());
  for (Eigen::Index i = 0; i < mean->size(); ++i) {
    BatchMeanAndError(
        static_cast<int>(batches.size()), [&](int b) { return batches[b].data()[i]; },
        &mean->data()[i], &standard_error->data()[i]);
  }
}

}  // namespace fenestra
