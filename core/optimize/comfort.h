#pragma once

// Comfort in the search (core/README.md, "Comfort in the search"): per design, beside the
// daylight metrics, the glare at the scene's view points and the solar energy its windows let
// in, so that a job can weigh them (objective, constraint, Pareto objective).
//
// - Glare: each view is a sensor at the eye facing the view direction, traced by the same
//   two-stage method as the sensors (its own indoor paths, the job's outdoor matrix and
//   split sky), E = (I O) S + E_sun with the sun's beam at the eye exact (direct_sun.h); per
//   occupied lit step the DGP with the sun as glare source (core/metrics/glare.h); glare
//   autonomy (steps below the threshold, mean over views) and hours of glare (steps in which
//   some view reaches it) over the occupied hours.
// - Solar gains: points on a plane just inside each window's blind (or glazing), facing out,
//   over the opening and a margin beside it that catches light leaving the blind obliquely;
//   every indoor surface but the window's reveal is black there, so a point's irradiance is
//   the solar radiation crossing the plane inwards through glazing and blind, not light the
//   room sends back. The product is taken through the solar sky summed over the year's and
//   the cooling season's steps (two columns: the gains are linear in the sky), the beam by
//   the direct sun's lines. The heat the slats absorb and give off again is left out.
// Standard errors by the delete-one jackknife over the batches, as the daylight metrics'.
#include <memory>
#include <vector>

#include "absl/status/statusor.h"
#include "core/common/radiance_matrix.h"
#include "core/common/vec3.h"
#include "core/dc/dc_backend.h"
#include "core/dc/direct_sun.h"
#include "core/dc/two_stage.h"
#include "core/geometry/scene.h"
#include "core/metrics/annual_metrics.h"
#include "core/metrics/glare.h"
#include "core/metrics/metric_errors.h"
#include "core/sky/sky_matrix.h"

namespace fenestra {

// Gain points per window (a fixed low-discrepancy pattern over its plane), and their paths
// as a share of the sensors' (Sampling.indoor_paths_per_sensor): the gains are a sum over
// many points, so each needs fewer.
inline constexpr int kGainPointsPerWindow = 64;
inline constexpr int kGainPathsDivisor = 32;
// How far the gain plane lies inside the blind's space (or the glazing's inner face) [m],
// and how far its margin reaches beside the opening per metre of that depth (light leaving
// the blind up to 72 degrees off the window's normal).
inline constexpr double kGainPlaneClearanceM = 0.01;
inline constexpr double kGainMarginPerDepth = 3;

// Which comfort metrics a job's search weighs.
struct ComfortNeeds {
  bool glare = false;
  bool gains = false;
  bool Any() const { return glare || gains; }
};
ComfortNeeds NeedsOf(std::span<const SceneMetric> metrics);

// The points the solar gains are summed over, each with the plane area it stands for [m2].
struct GainPoints {
  std::vector<Sensor> sensors;
  std::vector<double> area_m2;
};
GainPoints GainPointsOf(const Scene& scene);

// `scene` for the gains: the gain points as its sensors, no views, and every surface black
// but those within a window's zone (its reveal and the wall's inner face around it, up to
// its gain plane).
Scene GainScene(const Scene& scene, const GainPoints& points);

// The skies the comfort metrics are taken through, made once per job.
struct ComfortSky {
  // Glare: the job's lit analysed steps (ascending) and its split sky over them in lux, the
  // sun of each, the occupied ones, and the threshold
  std::vector<int> columns;
  Matrix lit_sky;
  std::vector<SunColumn> suns;
  std::vector<bool> occupied_column;
  int occupied_hours = 0;  // every occupied step, dark ones included: the denominator
  double glare_threshold = kDefaultGlareThreshold;
  // Gains: the split solar sky [W m-2 sr-1] summed over every lit step (column 0) and over
  // those of the cooling season (column 1), times the step's hour; the sun of every lit
  // step of the solar matrix and whether it is in the season
  Matrix gain_sky;
  std::vector<SunColumn> gain_suns;
  std::vector<bool> gain_in_season;  // per lit step, in gain_suns' column numbering
  int gain_columns = 0;
};

// Months 1-12 of the cooling season, start > end wrapping the new year.
struct CoolingSeason {
  int start_month = 5;
  int end_month = 9;
  bool Contains(int month) const {
    return start_month <= end_month ? month >= start_month && month <= end_month
                                    : month >= start_month || month <= end_month;
  }
};
// May to September north of the equator, November to March south of it.
CoolingSeason DefaultCoolingSeason(double latitude_deg);

// The gains' part of `sky` from the solar matrix `solar` (the same weather and steps).
absl::StatusOr<ComfortSky> MakeComfortSky(const SkyMatrix& visible, const SkyMatrix& solar,
                                          std::vector<int> columns,
                                          const std::vector<bool>& occupied, double glare_threshold,
                                          CoolingSeason season);

// The comfort metrics of one design, with standard errors.
struct ComfortEstimate {
  SceneMetrics value, standard_error;  // only the comfort fields set
  bool glare = false, gains = false;   // which of them
};

// The comfort metrics of a job's designs on one lane: on backends of their own on the lane's
// device (a GPU's tracer holds one set of records), the eyes' and the gain points' indoor
// paths recorded once, then per design replayed and taken through the skies.
class DesignComfort {
 public:
  // Records the paths (`ranged`: the job's scene, its blind's ranges the job's).
  // InvalidArgument for glare without views.
  static absl::StatusOr<std::unique_ptr<DesignComfort>> Start(const Scene& ranged,
                                                              const IndoorOptions& indoor,
                                                              const DcBackend& lane,
                                                              ComfortNeeds needs);
  ~DesignComfort();

  // Once the outdoor matrix and the skies are there: the products and the direct sun.
  absl::Status SetSky(const std::vector<Matrix>& outdoor_batches,
                      std::shared_ptr<const ComfortSky> sky);

  absl::StatusOr<ComfortEstimate> Evaluate(const BlindDesign& design);
  // Evaluate of each of `designs`, in their order (an error for one leaves the others): on
  // the GPU's replay several in one launch (DesignTallies::DesignsIlluminance).
  std::vector<absl::StatusOr<ComfortEstimate>> EvaluateDesigns(
      const std::vector<BlindDesign>& designs);
  // Closest-hit queries of every evaluation so far.
  uint64_t RaysTraced() const;
  // Wall time of every evaluation so far [s].
  double Seconds() const { return seconds_; }

 private:
  struct Part;
  DesignComfort() = default;
  // The figures of one design from its glare counts (DesignTallies::GlareDesigns) or its E
  // per batch (DesignTallies::DesignsIlluminance)
  void GlareOf(const BlindDesign& design, const GlareCounts& counts, ComfortEstimate& out) const;
  void GainsOf(const BlindDesign& design, const std::vector<Matrix>& batches,
               ComfortEstimate& out) const;

  ComfortNeeds needs_;
  std::vector<ViewPoint> views_;
  std::vector<double> gain_area_m2_;
  std::unique_ptr<Part> eyes_, gains_;
  std::shared_ptr<const ComfortSky> sky_;
  double seconds_ = 0;
};

// `estimate` with the comfort metrics of `comfort` (has_glare, has_gains as it has them).
void AddComfort(const ComfortEstimate& comfort, AnnualMetricsEstimate& estimate);

}  // namespace fenestra
