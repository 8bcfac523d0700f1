#pragma once

// The annual product of the two-stage method and its metric tallies on a GPU: E_b =
// (I_b O_b) S, then what the annual metrics need of E (core/metrics/annual_metrics.h,
// HourTally), reduced on the device so that E never leaves it. Host-only declarations (no
// CUDA headers); errors are statuses, as the tracer's (core/trace/cuda/cuda_tracer.h).
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/dc/sun_entry.h"

namespace fenestra {

// A design's direct-sun entries (core/dc/direct_sun.h), added to its E in every batch; the
// sky must then be split (2 x kTregenzaBinCount rows: S, then -S_sun for the indoor rows'
// unreflected direct columns, the last kTregenzaBinCount of each).
struct SunEntries {
  const SunEntry* entries = nullptr;
  size_t count = 0;
};

class CudaAnnualTally {
 public:
  // On CUDA device `device`; UNAVAILABLE where the host has no CUDA device.
  static absl::StatusOr<std::unique_ptr<CudaAnnualTally>> Create(int device);
  ~CudaAnnualTally();
  CudaAnnualTally(const CudaAnnualTally&) = delete;
  CudaAnnualTally& operator=(const CudaAnnualTally&) = delete;

  // Uploads the O_b (each cells x kTregenzaBinCount, row-major, one per batch; cells = the
  // columns of I) and S (`bins` x steps, row-major: kTregenzaBinCount, or twice that for a
  // split sky). The device keeps them until the next SetProduct. With `outdoor_on_device` the
  // O_b lie on this device already (a tracer's, CudaTracer::OutdoorOutput) and are copied
  // from there.
  absl::Status SetProduct(const std::vector<const double*>& outdoor, int cells, const double* sky,
                          int steps, int bins, bool outdoor_on_device = false);
  // Uploads S alone (`bins` rows), the O_b being the identity (`bins` cells): E_b = I_b S for
  // indoor rows whose columns are the sky's rows already (one-stage daylight coefficients, D or
  // [D | D_0]), in any number of batches from 2 to the most SetProduct takes. Kept until the
  // next SetProduct.
  absl::Status SetSkyProduct(const double* sky, int steps, int bins);
  // `rows` stacked indoor rows (rows x cells, batch-major, rows / B per batch) through the
  // product into `illuminance` (rows x steps). With `other_sky` (as S's rows x `other_steps`,
  // row-major) that sky takes S's place for this call, S staying uploaded. The direct sun is
  // the caller's to add.
  absl::Status Illuminance(const double* indoor, int rows, double* illuminance,
                           const double* other_sky = nullptr, int other_steps = 0);

  // Version 0 is E of the mean of the batches, version 1 + b the mean of the others
  // (B E - E_b) / (B - 1). Per version v and sensor i, counts[(v * sensors + i) * 3 + k] gets
  // the hours below `lower_lux`, above `upper_lux` and at or above `da_lux`,
  // sums[(v * sensors + i) * 2 + k] the sums of min(E / da_lux, 1) and of E; hours[v * 4 + k]
  // the hours with every sensor in range, some below, some above, and the entries that are
  // not finite.
  struct TallyRequest {
    double lower_lux, upper_lux, da_lux;
    int64_t* counts;
    double* sums;
    int64_t* hours;
  };
  // The tallies of E_b = (I_b O_b) S for the host's `indoor`, batches x sensors stacked rows
  // (batch-major), as many batches as the product's.
  absl::Status Tally(const double* indoor, int batches, int sensors, const TallyRequest& request,
                     SunEntries sun = {});
  // The same for `designs` designs at once from indoor sums on this device (a tracer's,
  // CudaTracer::DeviceSums): design k's row (b, s) at device_sums + k * design_sums +
  // (b * sensors + s) * cells, divided by batch_paths[b], the paths summed into batch b; its
  // tallies into requests[k]. One product takes every design's rows (a batch's rows
  // together), and the tallies come back in one download; design k's direct sun sun[k] is
  // added to its E. 1 <= designs.
  absl::Status TallySums(const double* device_sums, size_t design_sums, int designs, int batches,
                         int sensors, const uint64_t* batch_paths, const TallyRequest* requests,
                         const SunEntries* sun);
  // E_b = (I_b O_b) S' of one design's indoor sums on this device, as TallySums takes them,
  // into `illuminance` (batches x sensors rows, batch-major, x `other_steps`), with
  // `other_sky` (as S's rows x other_steps, row-major) as S' for this call; the direct sun is
  // the caller's to add.
  absl::Status IlluminanceOfSums(const double* device_sums, int batches, int sensors,
                                 const uint64_t* batch_paths, const double* other_sky,
                                 int other_steps, double* illuminance);

  // Glare at `views` eyes (core/dc/glare_tally.h), after SetProduct and fitting its steps:
  // per view and step the sun's geometric factor (`sun_factor`, views x steps, row-major),
  // per step whether it is occupied, the DGP threshold and the eye illuminance at which a
  // step without the sun reaches it. Kept until the next SetGlare.
  absl::Status SetGlare(const double* sun_factor, const uint8_t* occupied, int views,
                        double threshold, double eye_limit);
  // The glare counts of `designs` designs' indoor sums on this device, as TallySums takes
  // them (the sensors the views), design k's beam at the eyes sun[k]: per design, version v
  // (as the tallies') and view i, counts[(k * (batches + 1) + v) * (views + 1) + i] gets the
  // occupied steps in glare, and index views of each the steps in which some view is.
  absl::Status GlareSums(const double* device_sums, size_t design_sums, int designs, int batches,
                         const uint64_t* batch_paths, const SunEntries* sun, int64_t* counts);

  // Whether I_b O_b runs on the FP64 tensor cores: from Create on, where the device's code
  // has them (compute capability 8.0 and later); false takes the kernel of the CUDA cores
  // (the tests compare the two).
  void UseTensorCores(bool use);
  bool UsesTensorCores() const;

  // OK where the product pairs with indoor stages of `columns` columns in `batches` batches,
  // FAILED_PRECONDITION otherwise.
  absl::Status CheckPairs(int columns, int batches) const;

 private:
  struct Impl;
  explicit CudaAnnualTally(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace fenestra
