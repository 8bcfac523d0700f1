// The annual product E_b = (I_b O) S on the CPU: every batch in one pair of Eigen products
// (on all cores with OpenMP).
#include <utility>

#include "absl/strings/str_cat.h"
#include "core/dc/dc_backend.h"

namespace fenestra {
namespace {

class CpuAnnualProduct : public AnnualProduct {
 public:
  CpuAnnualProduct(Matrix outdoor, Matrix sky)
      : outdoor_(std::move(outdoor)), sky_(std::move(sky)) {}

  absl::StatusOr<std::vector<Matrix>> Apply(const std::vector<Matrix>& indoor_batches) override {
    if (indoor_batches.empty()) return std::vector<Matrix>{};
    const Eigen::Index rows = indoor_batches[0].rows();
    Matrix stacked(rows * static_cast<Eigen::Index>(indoor_batches.size()), outdoor_.rows());
    for (size_t b = 0; b < indoor_batches.size(); ++b) {
      if (indoor_batches[b].rows() != rows || indoor_batches[b].cols() != outdoor_.rows()) {
        return absl::InvalidArgumentError(absl::StrCat(
            "indoor batch ", b, " is ", indoor_batches[b].rows(), " x ", indoor_batches[b].cols(),
            ", the outdoor matrix has ", outdoor_.rows(), " window cells"));
      }
      stacked.middleRows(b * rows, rows) = indoor_batches[b];
    }
    const Matrix illuminance = (stacked * outdoor_) * sky_;
    std::vector<Matrix> batches;
    for (size_t b = 0; b < indoor_batches.size(); ++b) {
      batches.push_back(illuminance.middleRows(b * rows, rows));
    }
    return batches;
  }

 private:
  Matrix outdoor_, sky_;
};

}  // namespace

absl::StatusOr<std::unique_ptr<AnnualProduct>> DcBackend::MakeAnnualProduct(const Matrix& outdoor,
                                                                            const Matrix& sky) {
  if (outdoor.cols() != sky.rows()) {
    return absl::InvalidArgumentError(
        absl::StrCat("the outdoor matrix has ", outdoor.cols(), " sky bins, the sky ", sky.rows()));
  }
  return std::make_unique<CpuAnnualProduct>(outdoor, sky);
}

}  // namespace fenestra
