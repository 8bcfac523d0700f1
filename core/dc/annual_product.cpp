// The annual product E_b = (I_b O_b) S on the CPU (Eigen, on all cores), and the tallies
// of E for the metrics.
#include <utility>

#include "absl/strings/str_cat.h"
#include "core/common/status_macros.h"
#include "core/dc/backend_support.h"
#include "core/dc/dc_backend.h"
#include "core/dc/direct_sun.h"
#include "core/metrics/metric_errors.h"

namespace fenestra {
namespace {

// Without O_b (empty `outdoor`), the product of the sky alone (DcBackend::MakeSkyProduct).
class CpuAnnualProduct : public AnnualProduct {
 public:
  CpuAnnualProduct(std::vector<Matrix> outdoor, Matrix sky)
      : outdoor_(std::move(outdoor)), sky_(std::move(sky)) {}

  absl::StatusOr<std::vector<Matrix>> ApplyToSky(const std::vector<Matrix>& indoor_batches,
                                                 const Matrix& sky,
                                                 std::span<const SunEntry> sun) override {
    FENESTRA_ASSIGN_OR_RETURN(stacked, StackedIlluminance(indoor_batches, sky, sun));
    return SplitBatches(stacked, indoor_batches.size());
  }
  // From E as the product makes it, the batches stacked, not copied apart
  absl::StatusOr<std::vector<HourTally>> Tally(const std::vector<Matrix>& indoor_batches,
                                               const MetricOptions& options,
                                               std::span<const SunEntry> sun) override {
    FENESTRA_ASSIGN_OR_RETURN(stacked, StackedIlluminance(indoor_batches, sky_, sun));
    return TallyStackedVersions(stacked, static_cast<int>(indoor_batches.size()), options);
  }
  const Matrix& Sky() const override { return sky_; }

 private:
  // E_b of every batch through `sky`, batch b's rows from b n on, the sun's entries added.
  absl::StatusOr<Matrix> StackedIlluminance(const std::vector<Matrix>& indoor_batches,
                                            const Matrix& sky,
                                            std::span<const SunEntry> sun) const {
    FENESTRA_RETURN_IF_ERROR(CheckSkyRows(sky));
    const bool split = sky.rows() == kSplitSkyRows;
    Matrix e;
    if (outdoor_.empty()) {
      // One-stage rows: D, or [D | D_0] for a split sky
      FENESTRA_ASSIGN_OR_RETURN(stacked, StackIndoorBatches(indoor_batches, sky.rows()));
      e = ProductOnAllCores(stacked, sky);
    } else {
      FENESTRA_RETURN_IF_ERROR(CheckPairs(indoor_batches, outdoor_));
      // Every batch's light through the window, then all batches' E in one product
      e = ProductOnAllCores(ThroughWindow(indoor_batches, outdoor_, split), sky);
    }
    FENESTRA_RETURN_IF_ERROR(CheckSunEntries(sun, indoor_batches, sky));
    AddSunEntries(sun, indoor_batches.empty() ? 0 : static_cast<int>(indoor_batches[0].rows()), e);
    return e;
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
