// The annual product E_b = (I_b O) S on the CPU: every batch in one pair of Eigen products
// (on all cores with OpenMP); the default tallies of E for the metrics.
#include <utility>

#include "absl/strings/str_cat.h"
#include "core/common/status_macros.h"
#include "core/dc/backend_support.h"
#include "core/dc/dc_backend.h"
#include "core/metrics/metric_errors.h"

namespace fenestra {
namespace {

class CpuAnnualProduct : public AnnualProduct {
 public:
  CpuAnnualProduct(Matrix outdoor, Matrix sky)
      : outdoor_(std::move(outdoor)), sky_(std::move(sky)) {}

  absl::StatusOr<std::vector<Matrix>> Apply(const std::vector<Matrix>& indoor_batches) override {
    FENESTRA_ASSIGN_OR_RETURN(stacked, StackIndoorBatches(indoor_batches, outdoor_.rows()));
    return SplitBatches((stacked * outdoor_) * sky_, indoor_batches.size());
  }

 private:
  Matrix outdoor_, sky_;
};

}  // namespace

absl::StatusOr<std::vector<HourTally>> AnnualProduct::Tally(
    const std::vector<Matrix>& indoor_batches, const MetricOptions& options) {
  FENESTRA_ASSIGN_OR_RETURN(illuminance, Apply(indoor_batches));
  return TallyBatchVersions(illuminance, options);
}

absl::StatusOr<std::unique_ptr<AnnualProduct>> DcBackend::MakeAnnualProduct(const Matrix& outdoor,
                                                                            const Matrix& sky) {
  if (outdoor.cols() != sky.rows()) {
    return absl::InvalidArgumentError(
        absl::StrCat("the outdoor matrix has ", outdoor.cols(), " sky bins, the sky ", sky.rows()));
  }
  return std::make_unique<CpuAnnualProduct>(outdoor, sky);
}

}  // namespace fenestra
