#pragma once

// A blind operated by IES LM-83's rule (VenetianBlind AUTOMATED_SUN; core/README.md, "Operated
// blinds"): in place in the hours in which more than operation_sensor_percent of the sensors
// get more than operation_threshold_lux of direct sun through the bare window, retracted
// otherwise. The rule reads the bare window's direct sun alone, so which hours have the blind
// in place does not depend on the design: a design's E is its own in those hours and the bare
// window's in the others. The annual tallies add up over hours, so a design's are the tallies
// of its closed hours plus those of the bare window's open hours, traced once per job. ASE is
// the bare window's (LM-83: operable shading retracted).
#include <memory>
#include <vector>

#include "absl/status/statusor.h"
#include "core/dc/dc_backend.h"
#include "core/dc/direct_sun.h"
#include "core/dc/two_stage.h"
#include "core/metrics/annual_metrics.h"
#include "fenestra/v1/job.pb.h"

namespace fenestra {

// Which of a product's columns the rule closes, from the bare window's direct sun over them
// (sensors x columns, lx).
std::vector<bool> BlindInPlace(const Matrix& bare_direct_lux, const MetricOptions& options);

// `a` + `b`: tallies of the same sensors over disjoint hours. InvalidArgument for other
// sensor counts.
absl::StatusOr<HourTally> AddTallies(const HourTally& a, const HourTally& b);

// What a job with an operated blind evaluates its designs with.
struct BlindOperation {
  std::vector<bool> in_place;                   // per column of the job's sky
  std::vector<int> closed;                      // the columns with the blind in place
  Matrix closed_sky;                            // the split sky over them
  std::shared_ptr<const DirectSun> closed_sun;  // the direct sun over them, blind and all
  // The bare window: its tallies over the open columns (per version), its sunlit hours over
  // all columns (ASE), its indoor batches (for its hourly illuminance)
  std::vector<HourTally> open;
  std::vector<int64_t> bare_sunlit;
  std::vector<Matrix> bare_indoor;
};

// The operation of `scene`'s blind (AUTOMATED_SUN) over the columns of the split sky
// `sky` whose suns are `suns` and direct sun `sun` (DirectSun over those columns): the rule's
// hours from the bare window's direct sun, the bare window's indoor stage (`indoor`, on
// `backend`) through O_b (`outdoor_batches`) over the open columns.
absl::StatusOr<BlindOperation> OperateBlind(const Scene& scene, const Matrix& sky,
                                            const std::vector<SunColumn>& suns,
                                            const DirectSun& sun,
                                            const std::vector<Matrix>& outdoor_batches,
                                            const IndoorOptions& indoor,
                                            const MetricOptions& options, DcBackend& backend);

// `design`'s hourly illuminance (every step) where `in_place` (per step), the bare window's
// `bare` elsewhere; blind_in_place set from `in_place`.
void MixOperatedHours(const std::vector<bool>& in_place, const v1::HourlyIlluminance& bare,
                      v1::HourlyIlluminance& design);

// A design's tallies over the whole year from `closed`, its tallies over op.closed: plus
// the bare window's over the open columns, with the bare window's sunlit hours and the hours
// the blind is in place. InvalidArgument where the versions differ.
absl::StatusOr<std::vector<HourTally>> WithOpenHours(absl::StatusOr<std::vector<HourTally>> closed,
                                                     const BlindOperation& op);

// The same with the bare window's tallies of its mean (op.open[0]) added to every version of
// `closed`, in any number: where the bare window's hours are the same in both estimates a
// comparison takes (the final check's), so that its batches need not pair with the design's.
absl::StatusOr<std::vector<HourTally>> WithOpenMean(absl::StatusOr<std::vector<HourTally>> closed,
                                                    const BlindOperation& op);

// Design tallies of an operated blind: `closed`'s (its product over op.closed, its direct sun
// there; core/optimize/job.cpp sets them) with the open hours added (WithOpenHours).
class OperatedDesignTallies : public DesignTallies {
 public:
  OperatedDesignTallies(std::unique_ptr<DesignTallies> closed,
                        std::shared_ptr<const BlindOperation> operation)
      : closed_(std::move(closed)), op_(std::move(operation)) {}

  absl::StatusOr<std::vector<HourTally>> Tally(const BlindDesign& design,
                                               const MetricOptions& options,
                                               int parts = kDesignParts) override;
  std::vector<absl::StatusOr<std::vector<HourTally>>> TallyDesigns(
      const std::vector<BlindDesign>& designs, const MetricOptions& options) override;
  absl::StatusOr<std::vector<Matrix>> IndoorBatches(const BlindDesign& design) override {
    return closed_->IndoorBatches(design);
  }
  absl::StatusOr<std::vector<Matrix>> DesignIlluminance(const BlindDesign& design,
                                                        const Matrix& sky) override {
    return closed_->DesignIlluminance(design, sky);
  }
  absl::Status SetProduct(const std::vector<Matrix>& outdoor_batches, const Matrix& sky,
                          const DeviceMatrices& on_device) override {
    return closed_->SetProduct(outdoor_batches, sky, on_device);
  }
  AnnualProduct* Product() override { return closed_->Product(); }
  int DesignsAtOnce() const override { return closed_->DesignsAtOnce(); }
  bool TracesInParts() const override { return closed_->TracesInParts(); }
  bool RacesByDefault() const override { return closed_->RacesByDefault(); }
  uint64_t RaysTraced() const override { return closed_->RaysTraced(); }

 private:
  std::unique_ptr<DesignTallies> closed_;
  std::shared_ptr<const BlindOperation> op_;
};

}  // namespace fenestra
