#include "core/optimize/operated_blind.h"

#include "absl/strings/str_cat.h"
#include "core/common/status_macros.h"

namespace fenestra {

std::vector<bool> BlindInPlace(const Matrix& bare_direct_lux, const MetricOptions& options) {
  std::vector<bool> in_place(bare_direct_lux.cols(), false);
  const double sensors = static_cast<double>(bare_direct_lux.rows());
  for (Eigen::Index c = 0; c < bare_direct_lux.cols(); ++c) {
    const double sunlit = static_cast<double>(
        (bare_direct_lux.col(c).array() > options.operation_threshold_lux).count());
    // Counts, not rounded shares: more than the share of the sensors
    in_place[c] = sunlit * 100.0 > options.operation_sensor_percent * sensors;
  }
  return in_place;
}

absl::StatusOr<HourTally> AddTallies(const HourTally& a, const HourTally& b) {
  if (a.sensors.size() != b.sensors.size()) {
    return absl::InvalidArgumentError(
        absl::StrCat("tallies of ", a.sensors.size(), " and ", b.sensors.size(), " sensors"));
  }
  HourTally sum = a;
  for (size_t i = 0; i < sum.sensors.size(); ++i) {
    SensorHourTally& s = sum.sensors[i];
    const SensorHourTally& t = b.sensors[i];
    s.below += t.below, s.above += t.above, s.da += t.da;
    s.credit += t.credit, s.sum += t.sum;
  }
  sum.hours += b.hours;
  sum.all_in += b.all_in, sum.any_below += b.any_below, sum.any_above += b.any_above;
  return sum;
}

namespace {

// Columns `columns` of `m`.
Matrix Columns(const Matrix& m, const std::vector<int>& columns) {
  Matrix out(m.rows(), static_cast<Eigen::Index>(columns.size()));
  for (size_t c = 0; c < columns.size(); ++c) out.col(c) = m.col(columns[c]);
  return out;
}

// The suns of `suns` whose columns are among `columns`, their columns numbered as there.
std::vector<SunColumn> SunsOf(const std::vector<SunColumn>& suns, const std::vector<int>& columns,
                              int all_columns) {
  std::vector<int> index(all_columns, -1);
  for (size_t c = 0; c < columns.size(); ++c) index[columns[c]] = static_cast<int>(c);
  std::vector<SunColumn> out;
  for (SunColumn sun : suns) {
    if (index[sun.column] < 0) continue;
    sun.column = index[sun.column];
    out.push_back(sun);
  }
  return out;
}

// The bare window's tallies over `columns` of `sky`, every version, its direct sun added.
absl::StatusOr<std::vector<HourTally>> BareTallies(const std::vector<Matrix>& bare_indoor,
                                                   const Matrix& sky, const Matrix& bare_direct,
                                                   const std::vector<int>& columns,
                                                   const std::vector<Matrix>& outdoor_batches,
                                                   const MetricOptions& options,
                                                   DcBackend& backend) {
  const int sensors = static_cast<int>(bare_direct.rows());
  if (columns.empty()) {
    HourTally none;
    none.sensors.resize(sensors);
    return std::vector<HourTally>(bare_indoor.size() + 1, none);
  }
  FENESTRA_ASSIGN_OR_RETURN(product,
                            backend.MakeAnnualProduct(outdoor_batches, Columns(sky, columns)));
  std::vector<SunEntry> entries;
  for (int s = 0; s < sensors; ++s) {
    for (size_t c = 0; c < columns.size(); ++c) {
      const double lux = bare_direct(s, columns[c]);
      if (lux > 0) entries.push_back({s, static_cast<int32_t>(c), lux});
    }
  }
  return product->Tally(bare_indoor, options, entries);
}

}  // namespace

absl::StatusOr<BlindOperation> OperateBlind(const Scene& scene, const Matrix& sky,
                                            const std::vector<SunColumn>& suns,
                                            const DirectSun& sun,
                                            const std::vector<Matrix>& outdoor_batches,
                                            const IndoorOptions& indoor,
                                            const MetricOptions& options, DcBackend& backend) {
  BlindOperation op;
  const Matrix bare_direct = sun.Illuminance(BlindDesign{}, /*blind=*/false);
  op.in_place = BlindInPlace(bare_direct, options);
  std::vector<int> open;
  for (size_t c = 0; c < op.in_place.size(); ++c) {
    (op.in_place[c] ? op.closed : open).push_back(static_cast<int>(c));
  }
  op.closed_sky = Columns(sky, op.closed);
  FENESTRA_ASSIGN_OR_RETURN(
      closed_sun, DirectSun::Trace(scene, SunsOf(suns, op.closed, static_cast<int>(sky.cols())),
                                   static_cast<int>(op.closed.size())));
  op.closed_sun = std::move(closed_sun);
  op.bare_sunlit = SunlitHours(bare_direct, options);
  // The bare window's paths (the design without its blind), once
  FENESTRA_ASSIGN_OR_RETURN(bare, ComputeIndoorStage(scene, BlindDesign{}, indoor, &backend));
  op.bare_indoor = std::move(bare.batches);
  FENESTRA_ASSIGN_OR_RETURN(open_tallies, BareTallies(op.bare_indoor, sky, bare_direct, open,
                                                      outdoor_batches, options, backend));
  op.open = std::move(open_tallies);
  return op;
}

void MixOperatedHours(const std::vector<bool>& in_place, const v1::HourlyIlluminance& bare,
                      v1::HourlyIlluminance& design) {
  const int steps = static_cast<int>(in_place.size());
  if (steps == 0 || design.illuminance_lux_size() != bare.illuminance_lux_size()) return;
  // The direct sun of either where there is any
  const int values = design.illuminance_lux_size();
  if (design.direct_sun_lux_size() != values && bare.direct_sun_lux_size() == values) {
    design.mutable_direct_sun_lux()->Resize(values, 0.0f);
  }
  const bool bare_sun = bare.direct_sun_lux_size() == values;
  for (int k = 0; k < values; ++k) {
    if (in_place[k % steps]) continue;
    design.set_illuminance_lux(k, bare.illuminance_lux(k));
    design.set_standard_error_lux(k, bare.standard_error_lux(k));
    if (design.direct_sun_lux_size() == values) {
      design.set_direct_sun_lux(k, bare_sun ? bare.direct_sun_lux(k) : 0.0f);
    }
  }
  design.clear_blind_in_place();
  for (const bool b : in_place) design.add_blind_in_place(b);
}

absl::StatusOr<std::vector<HourTally>> WithOpenHours(absl::StatusOr<std::vector<HourTally>> closed,
                                                     const BlindOperation& op) {
  if (!closed.ok()) return closed;
  if (closed->size() != op.open.size()) {
    return absl::InvalidArgumentError(absl::StrCat(
        "the design has ", closed->size(), " tally versions, the bare window ", op.open.size()));
  }
  std::vector<HourTally> out;
  for (size_t v = 0; v < op.open.size(); ++v) {
    FENESTRA_ASSIGN_OR_RETURN(sum, AddTallies((*closed)[v], op.open[v]));
    sum.sunlit = op.bare_sunlit;
    sum.blind_hours = static_cast<int64_t>(op.closed.size());
    out.push_back(std::move(sum));
  }
  return out;
}

absl::StatusOr<std::vector<HourTally>> WithOpenMean(absl::StatusOr<std::vector<HourTally>> closed,
                                                    const BlindOperation& op) {
  if (!closed.ok()) return closed;
  if (op.open.empty()) return absl::InvalidArgumentError("the bare window has no tallies");
  BlindOperation mean = op;
  mean.open.assign(closed->size(), op.open[0]);
  return WithOpenHours(std::move(closed), mean);
}

namespace {

// The tallies of no hour, as many versions as `op`'s.
std::vector<HourTally> NoHours(const BlindOperation& op) {
  HourTally none;
  none.sensors.resize(op.open.empty() ? 0 : op.open[0].sensors.size());
  return std::vector<HourTally>(op.open.size(), none);
}

}  // namespace

absl::StatusOr<std::vector<HourTally>> OperatedDesignTallies::Tally(const BlindDesign& design,
                                                                    const MetricOptions& options,
                                                                    int parts) {
  // A blind never in place: every design is the bare window
  if (op_->closed.empty()) return WithOpenHours(NoHours(*op_), *op_);
  return WithOpenHours(closed_->Tally(design, options, parts), *op_);
}

std::vector<absl::StatusOr<std::vector<HourTally>>> OperatedDesignTallies::TallyDesigns(
    const std::vector<BlindDesign>& designs, const MetricOptions& options) {
  if (op_->closed.empty()) {
    return std::vector<absl::StatusOr<std::vector<HourTally>>>(designs.size(),
                                                               WithOpenHours(NoHours(*op_), *op_));
  }
  std::vector<absl::StatusOr<std::vector<HourTally>>> out = closed_->TallyDesigns(designs, options);
  for (auto& versions : out) versions = WithOpenHours(std::move(versions), *op_);
  return out;
}

}  // namespace fenestra
