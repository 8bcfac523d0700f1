// Standard errors of the annual metrics from the Monte Carlo error of the daylight
// coefficients, by the delete-one jackknife over independent batches (Efron & Stein 1981;
// Efron & Tibshirani, "An Introduction to the Bootstrap", ch. 11).
//
// The caller splits the paths of each sensor into B >= 2 equal, independent batches and
// estimates D_1 .. D_B from them, so D = mean of D_b. The point estimate is the metric of D;
// the leave-one-out value theta_(-b) is the metric of the mean of the other B - 1 batches,
// and SE = sqrt((B-1)/B sum_b (theta_(-b) - mean theta_(-.))^2). This copes with the
// thresholds in UDI, DA, sDA that make the metrics non-linear in D; for a linear metric
// it equals the classical standard error of a mean of B batch values. Illuminance is
// linear in D, so E_(-b) = (B E - E_b) / (B - 1) from E = D S and E_b = D_b S: one product
// per batch, and only the analysed time steps are multiplied. Each version of E (the mean
// and the B leave-one-out) is reduced to an HourTally (annual_metrics.h) before its metrics
// are taken, so a GPU can form and tally the versions where E is and return only tallies.
//
// The direct-only illuminance for ASE, when given, is taken as exact (no batches): the ASE
// standard errors come out 0.
#pragma once

#include <span>
#include <vector>

#include "absl/status/statusor.h"
#include "core/common/radiance_matrix.h"
#include "core/metrics/annual_metrics.h"

namespace fenestra {

struct AnnualMetricsEstimate {
  AnnualMetrics value;           // the metrics of the mean over all batches
  AnnualMetrics standard_error;  // same layout; analysed_hours and has_ase copied
  int batches = 0;
  // The comfort metrics (SceneMetrics) computed: glare, solar gains
  bool has_glare = false;
  bool has_gains = false;
};

// The jackknife standard error from the B leave-one-out values; 0 when B < 2.
double JackknifeStandardError(std::span<const double> leave_one_out_values);

// InvalidArgument unless there are at least 2 batches, which standard errors need.
absl::Status CheckErrorBatches(int batches);

// The tallies of the versions of E that AnnualMetricsFromTallies takes, from B >= 2 batch
// illuminances (each n x hours, lx, every column an analysed hour): E = mean of the E_b,
// then each E_(-b) = (B E - E_b) / (B - 1). Assumes valid options (CheckMetricOptions).
// InvalidArgument for fewer than 2 batches, batches of different shapes or a non-finite value.
absl::StatusOr<std::vector<HourTally>> TallyBatchVersions(
    std::span<const Matrix> illuminance_batches_lux, const MetricOptions& options);

// TallyBatchVersions of B batches stacked in `stacked` (B n x hours, batch b's n rows from
// row b n on), as the annual products make them, without copying them apart. InvalidArgument
// for fewer than 2 batches, rows that do not split into B, or a non-finite value.
absl::StatusOr<std::vector<HourTally>> TallyStackedVersions(const Matrix& stacked, int batches,
                                                            const MetricOptions& options);

// Metrics and standard errors from the tallies of the versions of E: versions[0] of the mean
// of the B >= 2 batches, versions[1 + b] of E_(-b), the hours beyond them dark as in
// MetricsFromTally; no ASE. InvalidArgument for fewer than 3 versions, versions that differ
// in sensors or hours, no sensors, analysed_hours < 1 or below the tallied hours, bad options.
// `version_metrics` (may be null) gets each version's metrics, in the order of `versions`.
absl::StatusOr<AnnualMetricsEstimate> AnnualMetricsFromTallies(
    std::span<const HourTally> versions, int analysed_hours, const MetricOptions& options,
    std::vector<AnnualMetrics>* version_metrics = nullptr);

// Metrics and standard errors from B >= 2 batch estimates of grey daylight coefficients
// (each n x m) under a sky of 1 or 3 channels (illuminance.h); `columns`, `occupied`,
// `options` and `direct_illuminance_lux` (n x columns.size(), may be null) as in
// ComputeAnnualMetrics. InvalidArgument for fewer than 2 batches or mismatched shapes.
absl::StatusOr<AnnualMetricsEstimate> AnnualMetricsWithErrors(
    std::span<const Matrix> dc_batches, std::span<const Matrix> sky_channels,
    std::span<const int> columns, const std::vector<bool>& occupied,
    const MetricOptions& options = {}, const Matrix* direct_illuminance_lux = nullptr);

// The same from B >= 2 batch illuminances (each n x columns.size(), lx) formed by the
// caller, e.g. from coloured coefficients.
absl::StatusOr<AnnualMetricsEstimate> AnnualMetricsFromIlluminanceBatches(
    std::span<const Matrix> illuminance_batches_lux, std::span<const int> columns,
    const std::vector<bool>& occupied, const MetricOptions& options = {},
    const Matrix* direct_illuminance_lux = nullptr);

}  // namespace fenestra
