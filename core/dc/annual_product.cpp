// The annual product E_b = (I_b O_b) S on the CPU (Eigen, on all cores), and the tallies
// of E for the metrics.
#include <utility>

#include "absl/strings/str_cat.h"
#include "core/common/status_macros.h"
#include "core/dc/backend_support.h"
#include "core/dc/dc_backend.h"
#include "core/metrics/metric_errors.h"

namespace fenestra {
namespace {

// Without O_b (empty `outdoor`), the product of the sky alone (DcBackend::MakeSkyProduct).
class CpuAnnualProduct : public AnnualProduct {
 public:
  CpuAnnualProduct(std::vector<Matrix> outdoor, Matrix sky)
      : outdoor_(std::move(outdoor)), sky_(std::move(sky)) {}

  absl::StatusOr<std::vector<Matrix>> Apply(const std::vector<Matrix>& indoor_batches) override {
    return ApplyToSky(indoor_batches, sky_);
  }
  absl::StatusOr<std::vector<Matrix>> ApplyToSky(const std::vector<Matrix>& indoor_batches,
                                                 const Matrix& sky) override {
    FENESTRA_ASSIGN_OR_RETURN(stacked, StackedIlluminance(indoor_batches, sky));
    return SplitBatches(stacked, indoor_batches.size());
  }
  // From E as the product makes it, the batches stacked, not copied apart
  absl::StatusOr<std::vector<HourTally>> Tally(const std::vector<Matrix>& indoor_batches,
                                               const MetricOptions& options) override {
    FENESTRA_ASSIGN_OR_RETURN(stacked, StackedIlluminance(indoor_batches, sky_));
    return TallyStackedVersions(stacked, static_cast<int>(indoor_batches.size()), options);
  }

 private:
  // E_b of every batch through `sky`, batch b's rows from b n on.
  absl::StatusOr<Matrix> StackedIlluminance(const std::vector<Matrix>& indoor_batches,
                                            const Matrix& sky) const {
    FENESTRA_RETURN_IF_ERROR(CheckSkyRows(sky));
    if (outdoor_.empty()) {
      FENESTRA_ASSIGN_OR_RETURN(stacked, StackIndoorBatches(indoor_batches, kDaylightBins));
      return ProductOnAllCores(stacked, sky);
    }
    FENESTRA_RETURN_IF_ERROR(CheckPairs(indoor_batches, outdoor_));
    // Every batch's light through the window, then all batches' E in one product
    return ProductOnAllCores(ThroughWindow(indoor_batches, outdoor_), sky);
  }

  std::vector<Matrix> outdoor_;
  Matrix sky_;
};

}  // namespace

absl::StatusOr<std::unique_ptr<AnnualProduct>> DcBackend::MakeAnnualProduct(
    const std::vector<Matrix>& outdoor_batches, const Matrix& sky) {
  FENESTRA_RETURN_IF_ERROR(CheckOutdoorBatches(outdoor_batches, sky));
  return std::make_unique<CpuAnnualProduct>(outdoor_batches, sky);
}

absl::StatusOr<std::unique_ptr<AnnualProduct>> DcBackend::MakeSkyProduct(const Matrix& sky) {
  FENESTRA_RETURN_IF_ERROR(CheckSkyRows(sky));
  return std::make_unique<CpuAnnualProduct>(std::vector<Matrix>{}, sky);
}

}  // namespace fenestra
