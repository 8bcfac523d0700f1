// Climate-based annual daylight metrics per sensor and for the scene, with Honeybee's
// conventions (honeybee-radiance-postprocess metrics.py; IES LM-83 for sDA and ASE):
//
// - UDI[a,b] (Nabil & Mardaljevic 2005; upper limit 3000 lx as revised by Mardaljevic):
//   a <= E <= b, both limits inclusive; fell short: E < a, which includes every analysed
//   hour with the sun down; exceeded: E > b.
// - DA300: E >= 300 lx. Continuous DA: mean of min(E / 300, 1), partial credit below 300.
// - sDA300/50%: share of sensors whose DA300 >= 50%.
// - ASE1000,250: share of sensors whose direct-sun-only illuminance (sun alone, no
//   interreflection: Radiance -ab 0 with a sun-only sky) is > 1000 lx in >= 250 analysed
//   hours. It needs that illuminance as a separate matrix; without it ASE is not reported.
//
// The analysed hours (the denominator of every share) are the occupied steps (occupancy.h)
// by default, or every step of the year. The illuminance matrix holds only the time steps
// listed in `columns` (illuminance.h); every other step has E = 0 exactly. Shares are
// percentages, 0-100.
#pragma once

#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "absl/status/statusor.h"
#include "core/common/radiance_matrix.h"

namespace fenestra {

enum class HourBasis {
  kOccupied,  // the occupied steps (default, the field's convention)
  kAllHours,  // every step of the year
};

struct MetricOptions {
  double udi_lower_lux = 100;       // a, inclusive
  double udi_upper_lux = 3000;      // b, inclusive
  double da_threshold_lux = 300;    // DA counts E >= it; cDA credits min(E / it, 1)
  double sda_min_da_percent = 50;   // a sensor counts towards sDA when its DA >= it
  double ase_threshold_lux = 1000;  // direct-only E > it counts towards ASE
  int ase_min_hours = 250;          // a sensor counts towards ASE at >= this many hours
  // An operated blind (IES LM-83) is in place in an hour in which more than this share of the
  // sensors [%] gets more than operation_threshold_lux of direct sun through the bare window.
  double operation_sensor_percent = 2;
  double operation_threshold_lux = 1000;
  HourBasis hours = HourBasis::kOccupied;
};

// One sensor's metrics; shares in percent of the analysed hours.
struct SensorMetrics {
  double udi_percent = 0;             // a <= E <= b
  double udi_fell_short_percent = 0;  // E < a, dark hours included
  double udi_exceeded_percent = 0;    // E > b
  double da_percent = 0;              // E >= DA threshold
  double cda_percent = 0;             // mean of min(E / DA threshold, 1) x 100
  double mean_illuminance_lux = 0;    // mean E over the analysed hours
  double ase_hours = 0;               // analysed hours with direct-only E > ASE threshold
};

struct SceneMetrics {
  // Share of analysed hours in which every sensor is in [a, b]; hours in which at least one
  // sensor falls short / exceeds (an hour can do both, so the three may sum past 100).
  double udi_all_percent = 0;
  double udi_all_fell_short_percent = 0;
  double udi_all_exceeded_percent = 0;
  // The per-sensor shares averaged over sensors (Honeybee's and LM-83's aggregation).
  double udi_mean_percent = 0;
  double udi_mean_fell_short_percent = 0;
  double udi_mean_exceeded_percent = 0;
  double da_mean_percent = 0;
  double cda_mean_percent = 0;
  double sda_percent = 0;               // sensors with DA >= sda_min_da_percent
  double ase_percent = 0;               // sensors with ase_hours >= ase_min_hours; 0 without input
  double blind_in_place_percent = 100;  // analysed hours with the blind in place
  double mean_illuminance_lux = 0;      // over sensors and analysed hours
  // The comfort metrics (core/optimize/comfort.h); 0 where not computed
  double glare_autonomy_percent = 0;  // occupied hours with DGP below the threshold, mean of views
  double glare_hours_percent = 0;     // occupied hours in which some view's DGP reaches it
  double solar_gain_kwh = 0;          // transmitted through every window over the year
  double cooling_solar_gain_kwh = 0;  // the same over the cooling season
};

struct AnnualMetrics {
  int analysed_hours = 0;  // the denominator
  bool has_ase = false;    // a direct-only illuminance was given
  std::vector<SensorMetrics> sensors;
  SceneMetrics scene;
};

// The scene metrics by name, for objectives and reports.
enum class SceneMetric {
  kUdiAll,
  kUdiAllFellShort,
  kUdiAllExceeded,
  kUdiMean,
  kUdiMeanFellShort,
  kUdiMeanExceeded,
  kDaMean,
  kCdaMean,
  kSda,
  kAse,
  kMeanIlluminance,
  kBlindInPlace,
  // The comfort metrics (core/optimize/comfort.h), set only where a job weighs one
  kGlareAutonomy,
  kGlareHours,
  kSolarGain,
  kCoolingSolarGain,
};

// Whether `metric` is one of the comfort metrics, which the daylight tallies do not give.
inline bool IsComfortMetric(SceneMetric metric) { return metric >= SceneMetric::kGlareAutonomy; }

double SceneMetricValue(const SceneMetrics& scene, SceneMetric metric);

// LEED v4.1 daylight option 1 points from sDA300/50% [% of the sensors, all of equal area]:
// 1 from 40%, 2 from 55%, 3 from 75% (as Honeybee's LEED post-processing counts them); LEED
// asks ASE1000,250 to be at most 10% besides.
int LeedDaylightPoints(double sda_percent);

// Stable lower-case names: "udi_all", "udi_all_fell_short", "udi_all_exceeded", "udi_mean",
// "udi_mean_fell_short", "udi_mean_exceeded", "da_mean", "cda_mean", "sda", "ase",
// "mean_illuminance", "blind_in_place", "glare_autonomy", "glare_hours", "solar_gain",
// "cooling_solar_gain".
std::string_view SceneMetricName(SceneMetric metric);
// InvalidArgument listing the valid names when `name` is none of them.
absl::StatusOr<SceneMetric> SceneMetricFromName(std::string_view name);

// InvalidArgument naming the first inconsistent option.
absl::Status CheckMetricOptions(const MetricOptions& options);

// The analysed hours, the denominator of every share: the occupied steps, or with
// HourBasis::kAllHours every step (occupied.size()).
int AnalysedHours(const std::vector<bool>& occupied, HourBasis hours);

// One sensor's counts over the tallied hours: E < udi_lower_lux (below), E > udi_upper_lux
// (above), E >= da_threshold_lux (da); sums of min(E / da_threshold_lux, 1) (credit) and of
// E (sum, lx h).
struct SensorHourTally {
  int64_t below = 0, above = 0, da = 0;
  double credit = 0, sum = 0;
};

// All the UDI, DA, cDA, sDA and mean-illuminance metrics need of an illuminance: a few
// numbers per sensor, small enough for a GPU to reduce E to on the device. `hours` is the
// number of tallied (lit, analysed) hours; all_in / any_below / any_above count the hours
// in which every sensor is in [a, b] / some sensor falls short / some sensor exceeds.
struct HourTally {
  std::vector<SensorHourTally> sensors;
  int64_t hours = 0;
  int64_t all_in = 0, any_below = 0, any_above = 0;
  // Per sensor, where the direct sun is known (exactly, core/dc/direct_sun.h): the analysed
  // hours whose direct-sun illuminance exceeds ase_threshold_lux, for ASE; empty otherwise.
  std::vector<int64_t> sunlit;
  // Analysed hours with the blind in place (an operated blind); -1: all of them (static).
  int64_t blind_hours = -1;
};

// Per sensor, the hours of a sensors x hours direct-sun illuminance above the ASE threshold.
std::vector<int64_t> SunlitHours(const Matrix& direct_illuminance_lux,
                                 const MetricOptions& options);

// The tally of `illuminance_lux` (n sensors x hours, lx), every column an analysed hour.
// Assumes valid options (CheckMetricOptions).
HourTally TallyHours(const Matrix& illuminance_lux, const MetricOptions& options);

// TallyHours one sensor's row at a time: each row (`hours` values, lx) to AddRow, then
// Finish. The same sums in the same order, so the same tally to the last bit.
class HourTallyBuilder {
 public:
  HourTallyBuilder(int sensors, int64_t hours, const MetricOptions& options);
  // Sensor `sensor`'s row. Assumes valid options and a sensor within range.
  void AddRow(int sensor, const double* row);
  HourTally Finish();

 private:
  HourTally tally_;
  std::vector<uint8_t> any_below_, any_above_;  // per hour
  double lower_, upper_, da_;
};

// The metrics of a tally over `analysed_hours` >= tally.hours (> 0) hours, those beyond the
// tally being dark (E = 0); ASE where the tally has its sunlit hours (else has_ase false; see
// AddAse). Assumes valid options.
AnnualMetrics MetricsFromTally(const HourTally& tally, int analysed_hours,
                               const MetricOptions& options);

// Sets ASE in `metrics` (has_ase, each sensor's ase_hours, scene.ase_percent) from the
// direct-sun-only illuminance `direct_illuminance_lux` (n sensors x lit analysed hours, lx;
// the other analysed hours are dark).
void AddAse(const Matrix& direct_illuminance_lux, const MetricOptions& options,
            AnnualMetrics* metrics);

// Metrics of `illuminance_lux` (n sensors x columns.size(); column c is time step
// columns[c]). `occupied` has one flag per time step of the year and so also gives the
// number of steps; with HourBasis::kAllHours only its length is used.
// `direct_illuminance_lux`, when not null, is the direct-sun-only illuminance with the same
// shape and columns, for ASE. InvalidArgument for mismatched shapes, bad columns, non-finite
// illuminance, inconsistent options, no sensors or no analysed hours.
absl::StatusOr<AnnualMetrics> ComputeAnnualMetrics(const Matrix& illuminance_lux,
                                                   std::span<const int> columns,
                                                   const std::vector<bool>& occupied,
                                                   const MetricOptions& options = {},
                                                   const Matrix* direct_illuminance_lux = nullptr);

}  // namespace fenestra
