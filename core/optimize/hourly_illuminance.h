#pragma once

// The hourly illuminance of one design, for reports and other tools: from the design's
// indoor stage (the search's random streams), the backend's annual product
// E_b = (I_b O_b) S (core/dc/dc_backend.h) over every time step with daylight.
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "absl/status/statusor.h"
#include "core/common/radiance_matrix.h"
#include "core/dc/dc_backend.h"
#include "core/dc/direct_sun.h"
#include "core/dc/two_stage.h"
#include "core/geometry/scene.h"
#include "core/metrics/illuminance.h"
#include "core/sky/sky_matrix.h"
#include "fenestra/v1/job.pb.h"

namespace fenestra {

// The most sensors x time steps a job result holds hourly illuminance for (job.proto,
// JobResult.best_hourly): 8 MB of values and as much of errors.
inline constexpr int64_t kMaxHourlyIlluminanceValues = 2'000'000;

// Columns `columns` of a sky matrix's visible radiance [W sr-1 m-2] times the luminous
// efficacy, so that (I O) S comes out in lux.
// `scale`: units of the result per W sr-1 m-2 (the luminous efficacy; 1 for a solar matrix,
// whose products come out in W m-2).
Matrix SkyColumnsInLux(const Matrix& radiance, std::span<const int> columns,
                       double scale = kWhiteEfficacyLumensPerWatt);

// The split sky (kSplitSkyRows rows; core/README.md, "Direct sun") of columns `columns` of a
// Tregenza sky matrix with the sun, in lux: S, then -S_sun, the sun alone as the matrix
// spreads it over patches. InvalidArgument for a matrix of other bins.
// `scale` as SkyColumnsInLux's.
absl::StatusOr<Matrix> SplitSkyColumnsInLux(const SkyMatrix& sky, std::span<const int> columns,
                                            double scale = kWhiteEfficacyLumensPerWatt);

// The sun of each of `columns` that has one (SkyStep::direct_normal > 0, the disc's centre
// above the horizon), for the direct sun (core/dc/direct_sun.h); column c of the list is
// columns[c].
// `scale` as SkyColumnsInLux's (SunColumn::normal_lux then in its units).
std::vector<SunColumn> SunColumnsOf(const SkyMatrix& sky, std::span<const int> columns,
                                    double scale = kWhiteEfficacyLumensPerWatt);

// A design's E_b = (I_b O_b) S' through a sky S' in lux (as the product's rows x any steps),
// one per batch, the direct sun included where the sky is split:
// DesignTallies::DesignIlluminance, or AnnualProduct::ApplyToSky of the design's I_b.
using DesignIlluminanceOf = std::function<absl::StatusOr<std::vector<Matrix>>(const Matrix&)>;

// The illuminance of a design at every sensor of `scene` and every step of `sky`, the mean
// over the paired batches with its standard error (both stages' noise), from the design's
// E_b over the steps with daylight (`illuminance`, with the random streams of the search and
// the O_b of its outdoor stage) through the split sky, plus the design's direct sun `sun`
// (its columns the steps of `sky`; exact, so without error), also given apart (none where
// `sun` is empty). Which steps have the blind in place: `blind_in_place` per step, or every
// step where it is empty (then none is listed).
// InvalidArgument for fewer than 2 batches or a sun entry out of range; errors as
// `illuminance`.
absl::StatusOr<v1::HourlyIlluminance> DesignHourlyIlluminance(
    const Scene& scene, const SkyMatrix& sky, const DesignIlluminanceOf& illuminance,
    std::span<const SunEntry> sun, const std::vector<bool>& blind_in_place = {});

}  // namespace fenestra
