// The annual product and its tallies on the GPU (annual_tally.h).
#include <cuda_runtime.h>

#include <cstdint>
#include <cstring>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "core/common/status_macros.h"
#include "core/dc/cuda/annual_tally.h"
#include "core/dc/cuda/products.cuh"
#include "core/metrics/dgp_formula.h"
#include "core/metrics/hour_class.h"
#include "core/trace/cuda/device_buffer.cuh"
#include "core/trace/path.h"

namespace fenestra {
namespace {

// Batches the sums' normalization takes (kMaxBatches of the two-stage method).
constexpr int kMaxTallyBatches = 64;

// Transposes in kTile x kTile tiles through shared memory (TransposeKernel).
constexpr int kTile = 16;

// For a split sky: row r of `split` (rows x 2 kTregenzaBinCount) is row r of `through`, then
// the last kTregenzaBinCount columns of row r of `indoor` (rows x cells), its unreflected
// direct light.
__global__ void SplitRowsKernel(const double* through, const double* indoor, int cells,
                                double* split) {
  const int j = static_cast<int>(threadIdx.x);
  const size_t row = blockIdx.x;
  if (j >= 2 * kTregenzaBinCount) return;
  split[row * 2 * kTregenzaBinCount + j] =
      j < kTregenzaBinCount ? through[row * kTregenzaBinCount + j]
                            : indoor[row * cells + cells - 2 * kTregenzaBinCount + j];
}

// Adds each design's direct-sun entries to its E in every batch: entry e of design k to row
// (b * designs + k) * sensors + sensor, for every b.
__global__ void AddSunKernel(const SunEntry* entries, const int* design_of, int count, int designs,
                             int batches, int sensors, int steps, double* e) {
  const int i = static_cast<int>(blockIdx.x * blockDim.x + threadIdx.x);
  if (i >= count) return;
  const SunEntry entry = entries[i];
  for (int b = 0; b < batches; ++b) {
    const size_t row = (static_cast<size_t>(b) * designs + design_of[i]) * sensors + entry.sensor;
    e[row * steps + entry.column] += entry.lux;
  }
}

// Each batch's rows x columns matrix `in` (row-major, batch after batch) transposed into
// `out`, in kTile x kTile tiles through shared memory.
__global__ void TransposeKernel(const double* in, double* out, int rows, int columns) {
  __shared__ double tile[kTile][kTile + 1];
  const size_t offset = static_cast<size_t>(blockIdx.z) * rows * columns;
  const int column = static_cast<int>(blockIdx.x) * kTile + threadIdx.x;
  const int row = static_cast<int>(blockIdx.y) * kTile + threadIdx.y;
  if (row < rows && column < columns) {
    tile[threadIdx.y][threadIdx.x] = in[offset + static_cast<size_t>(row) * columns + column];
  }
  __syncthreads();
  const int out_row = static_cast<int>(blockIdx.x) * kTile + threadIdx.y;     // a column of in
  const int out_column = static_cast<int>(blockIdx.y) * kTile + threadIdx.x;  // a row of in
  if (out_row < columns && out_column < rows) {
    out[offset + static_cast<size_t>(out_row) * rows + out_column] = tile[threadIdx.x][threadIdx.y];
  }
}

// The paths summed into each batch.
struct BatchPaths {
  double paths[kMaxTallyBatches];
};

// I from the indoor sums of `designs` designs: design k's row (b, s) at sum + k *
// design_sums + (b * sensors + s) * cells, divided by batch b's paths as the host divides
// them (IndoorResultFromTally), into row (b * designs + k) * sensors + s of `indoor` (each
// batch's rows together, for the product with its O_b).
__global__ void BatchMeanKernel(const double* sum, size_t design_sums, int designs, int sensors,
                                int cells, BatchPaths batch, double* indoor) {
  const int cell = static_cast<int>(blockIdx.x * blockDim.x + threadIdx.x);
  if (cell >= cells) return;
  const int row = static_cast<int>(blockIdx.y);
  const int s = row % sensors, k = row / sensors % designs, b = row / (sensors * designs);
  const double value = sum[k * design_sums + (static_cast<size_t>(b) * sensors + s) * cells + cell];
  indoor[static_cast<size_t>(row) * cells + cell] = __ddiv_rn(value, batch.paths[b]);
}

// The metric thresholds of the tallies.
struct TallyLimits {
  double lower, upper, da;
  double batches, leave_one_out_scale;  // B and 1 / (B - 1)
};

// Where one design's tallies lie in the tallies buffer: the counts, the hours, then the sums
// (doubles), `total` entries per design.
struct TallyLayout {
  size_t counts, hours, total;
};

// One thread per (hour, version, design): E of the version (formed as the CPU forms it,
// without contracted multiply-adds), classified per sensor as the CPU classifies it
// (ClassifyHour); warps add their counts and sums to the version's totals. Design k's row
// (b, i) of E is (b * designs + k) * sensors + i.
__global__ void TallyKernel(const double* e, int designs, int batches, int sensors, int steps,
                            TallyLimits limits, TallyLayout layout, unsigned long long* tallies) {
  const int version = static_cast<int>(blockIdx.y);
  const int design = static_cast<int>(blockIdx.z);
  unsigned long long* counts = tallies + design * layout.total;
  unsigned long long* hours = counts + layout.counts;
  double* sums = reinterpret_cast<double*>(hours + layout.hours);
  const int t = static_cast<int>(blockIdx.x * blockDim.x + threadIdx.x);
  const bool active = t < steps;
  const unsigned all = 0xffffffffu;
  const bool leader = threadIdx.x % 32 == 0;
  bool any_below = false, any_above = false, non_finite = false;
  for (int i = 0; i < sensors; ++i) {
    double value = 0;
    if (active) {
      double total = 0;
      for (int b = 0; b < batches; ++b) {
        total = __dadd_rn(
            total, e[((static_cast<size_t>(b) * designs + design) * sensors + i) * steps + t]);
      }
      value = __ddiv_rn(total, limits.batches);
      if (version > 0) {
        const double left_out =
            e[((static_cast<size_t>(version - 1) * designs + design) * sensors + i) * steps + t];
        value = __dmul_rn(__dsub_rn(__dmul_rn(limits.batches, value), left_out),
                          limits.leave_one_out_scale);
      }
    }
    const HourClass c = ClassifyHour(value, limits.lower, limits.upper, limits.da);
    const bool below = active && c.below, above = active && c.above;
    any_below |= below;
    any_above |= above;
    non_finite |= active && !isfinite(value);
    double credit = active ? c.credit : 0.0, sum = value;
    for (int offset = 16; offset > 0; offset /= 2) {
      credit += __shfl_down_sync(all, credit, offset);
      sum += __shfl_down_sync(all, sum, offset);
    }
    const unsigned below_count = __popc(__ballot_sync(all, below));
    const unsigned above_count = __popc(__ballot_sync(all, above));
    const unsigned da_count = __popc(__ballot_sync(all, active && c.da));
    if (leader) {
      const size_t k = static_cast<size_t>(version) * sensors + i;
      if (below_count) atomicAdd(&counts[3 * k], below_count);
      if (above_count) atomicAdd(&counts[3 * k + 1], above_count);
      if (da_count) atomicAdd(&counts[3 * k + 2], da_count);
      atomicAdd(&sums[2 * k], credit);
      atomicAdd(&sums[2 * k + 1], sum);
    }
  }
  const unsigned in_range = __popc(__ballot_sync(all, active && !any_below && !any_above));
  const unsigned below = __popc(__ballot_sync(all, any_below));
  const unsigned above = __popc(__ballot_sync(all, any_above));
  const unsigned bad = __popc(__ballot_sync(all, non_finite));
  if (leader) {
    unsigned long long* h = hours + 4 * version;
    if (in_range) atomicAdd(&h[0], in_range);
    if (below) atomicAdd(&h[1], below);
    if (above) atomicAdd(&h[2], above);
    if (bad) atomicAdd(&h[3], bad);
  }
}

// Writes each design's direct-sun entries into its dense views x steps block of `sun`
// (zeroed before): entry e of design k to (k * views + sensor) * steps + column. The entries
// of a design are one per sensor and column (DirectSun::Entries).
__global__ void DenseSunKernel(const SunEntry* entries, const int* design_of, int count, int views,
                               int steps, double* sun) {
  const int i = static_cast<int>(blockIdx.x * blockDim.x + threadIdx.x);
  if (i >= count) return;
  const SunEntry entry = entries[i];
  sun[(static_cast<size_t>(design_of[i]) * views + entry.sensor) * steps + entry.column] =
      entry.lux;
}

// What decides a glare step (core/dc/glare_tally.h) beside the per-step tables.
struct GlareLimits {
  double threshold, eye_limit;
  double weight, leave_one_out_weight;  // 1 / B and 1 / (B - 1)
};

// One thread per (step, version, design): each view's E of the version, formed as the CPU's
// CountGlare forms it, then whether the step is glare there (Ev alone without the sun's
// beam at the eye, the DGP with the sun as source with it); warps add their counts to the
// version's. Design k's row (b, i) of E is (b * designs + k) * views + i; its counts at
// (k * versions + version) * (views + 1), the last the steps in which some view is in glare.
__global__ void GlareKernel(const double* e, const double* sun, const double* sun_factor,
                            const uint8_t* occupied, int designs, int batches, int views, int steps,
                            GlareLimits limits, unsigned long long* counts) {
  const int version = static_cast<int>(blockIdx.y);
  const int design = static_cast<int>(blockIdx.z);
  const int t = static_cast<int>(blockIdx.x * blockDim.x + threadIdx.x);
  const bool active = t < steps && occupied[t] != 0;
  const unsigned all = 0xffffffffu;
  unsigned long long* out =
      counts + (static_cast<size_t>(design) * (batches + 1) + version) * (views + 1);
  bool any = false;
  for (int i = 0; i < views; ++i) {
    bool glare = false;
    if (active) {
      double total = 0;
      for (int b = 0; b < batches; ++b) {
        total = __dadd_rn(total,
                          e[((static_cast<size_t>(b) * designs + design) * views + i) * steps + t]);
      }
      double value;
      if (version == 0) {
        value = __dmul_rn(limits.weight, total);
      } else {
        const double left_out =
            e[((static_cast<size_t>(version - 1) * designs + design) * views + i) * steps + t];
        value = __dmul_rn(limits.leave_one_out_weight, __dsub_rn(total, left_out));
      }
      const double beam = sun[(static_cast<size_t>(design) * views + i) * steps + t];
      if (beam == 0) {
        glare = value >= limits.eye_limit;
      } else if (beam > 0) {
        const double eye = __dadd_rn(0.0 < value ? value : 0.0, beam);
        glare = DgpWithSunFactor(eye, beam, sun_factor[static_cast<size_t>(i) * steps + t]) >=
                limits.threshold;
      }
    }
    any |= glare;
    const unsigned in_glare = __popc(__ballot_sync(all, glare));
    if (threadIdx.x % 32 == 0 && in_glare) atomicAdd(&out[i], in_glare);
  }
  const unsigned some = __popc(__ballot_sync(all, any));
  if (threadIdx.x % 32 == 0 && some) atomicAdd(&out[views], some);
}

absl::Status CheckBins(int bins) {
  if (bins != kTregenzaBinCount && bins != 2 * kTregenzaBinCount) {
    return absl::InvalidArgumentError(absl::StrCat("CUDA annual product: a sky of ", bins,
                                                   " rows, not ", kTregenzaBinCount, " or ",
                                                   2 * kTregenzaBinCount));
  }
  return absl::OkStatus();
}

absl::Status NoProduct() {
  return absl::FailedPreconditionError("CUDA annual product: no outdoor matrix and sky set");
}

}  // namespace

struct CudaAnnualTally::Impl {
  int device = 0;
  // O_b as uploaded and transposed, S, the indoor rows, I_b O_b and E; E's tallies
  DeviceBuffer<double> outdoor_rows, outdoor_transposed, sky, indoor, through_window, illuminance;
  DeviceBuffer<double> split_rows;  // through the window beside the unreflected light (split sky)
  DeviceBuffer<SunEntry> sun_entries;
  DeviceBuffer<int> sun_designs;
  DeviceBuffer<double> other_sky;  // a sky for one call to Illuminance
  // Glare at the eyes (SetGlare): the tables, the designs' dense sun and the counts
  DeviceBuffer<double> glare_factor, glare_sun;
  DeviceBuffer<uint8_t> glare_occupied;
  DeviceBuffer<unsigned long long> glare_counts;
  std::vector<unsigned long long> host_glare_counts;
  int glare_views = 0, glare_steps = 0;
  double glare_threshold = 0, eye_limit = 0;
  // E's tallies in one buffer, zeroed and downloaded at once (TallyLayout per design)
  DeviceBuffer<unsigned long long> tallies;
  std::vector<unsigned long long> host_tallies;
  PinnedBuffer staging;
  int cells = 0, steps = 0;      // cells: columns of I, rows of O_b
  int bins = kTregenzaBinCount;  // rows of S: the sky's bins, or a split sky's
  int outdoor_batches = 0;       // the O_b; 0 for the sky's product (sky_only)
  bool tensor_cores = false;     // I_b O_b by MultiplyTransposedMmaKernel
  bool sky_only = false;         // the O_b are the identity: E_b = I_b S (SetSkyProduct)

  absl::Status UploadIndoor(const double* host_indoor, int rows) {
    FENESTRA_CUDA_RETURN_IF_ERROR(cudaSetDevice(device));
    FENESTRA_CUDA_RETURN_IF_ERROR(indoor.Reserve(static_cast<size_t>(rows) * cells));
    FENESTRA_CUDA_RETURN_IF_ERROR(
        staging.Upload(host_indoor, indoor.get(), static_cast<size_t>(rows) * cells));
    return absl::OkStatus();
  }
  // `indoor` from indoor sums on the device (TallySums) for `designs` designs.
  absl::Status MeanOfSums(const double* device_sums, size_t design_sums, int designs, int batches,
                          int sensors, const uint64_t* batch_paths) {
    BatchPaths paths{};
    for (int b = 0; b < batches; ++b) paths.paths[b] = static_cast<double>(batch_paths[b]);
    const int rows = designs * batches * sensors;
    FENESTRA_CUDA_RETURN_IF_ERROR(cudaSetDevice(device));
    FENESTRA_CUDA_RETURN_IF_ERROR(indoor.Reserve(static_cast<size_t>(rows) * cells));
    const int threads = 256;
    const dim3 grid((cells + threads - 1) / threads, rows);
    BatchMeanKernel<<<grid, threads>>>(device_sums, design_sums, designs, sensors, cells, paths,
                                       indoor.get());
    FENESTRA_CUDA_RETURN_IF_ERROR(cudaGetLastError());
    return absl::OkStatus();
  }
  // E of `rows` rows of `indoor` (`batches` batches) into the host's `host_illuminance` (rows x
  // steps), through `other_sky` (kTregenzaBinCount x other_steps) in S's place where it is not
  // null.
  absl::Status DownloadIlluminance(int rows, int batches, double* host_illuminance,
                                   const double* other_sky, int other_steps) {
    const double* sky_matrix = nullptr;
    int sky_steps = steps;
    if (other_sky != nullptr) {
      FENESTRA_CUDA_RETURN_IF_ERROR(
          this->other_sky.Upload(other_sky, static_cast<size_t>(bins) * other_steps));
      sky_matrix = this->other_sky.get();
      sky_steps = other_steps;
    }
    FENESTRA_RETURN_IF_ERROR(FormIlluminance(rows, batches, sky_matrix, sky_steps));
    FENESTRA_CUDA_RETURN_IF_ERROR(staging.Download(illuminance.get(), host_illuminance,
                                                   static_cast<size_t>(rows) * sky_steps));
    return absl::OkStatus();
  }
  // E = (I O) S from `indoor` (`batches` batches of rows) into `illuminance`; with `sky_steps`
  // columns of `sky_matrix` in S's place where it is not null.
  absl::Status FormIlluminance(int rows, int batches, const double* sky_matrix = nullptr,
                               int sky_steps = 0) {
    if (sky_matrix == nullptr) {
      sky_matrix = sky.get();
      sky_steps = steps;
    }
    FENESTRA_CUDA_RETURN_IF_ERROR(illuminance.Reserve(static_cast<size_t>(rows) * sky_steps));
    const double* through = indoor.get();
    if (!sky_only) {
      FENESTRA_CUDA_RETURN_IF_ERROR(
          through_window.Reserve(static_cast<size_t>(rows) * kTregenzaBinCount));
      FENESTRA_CUDA_RETURN_IF_ERROR(
          MultiplyTransposed(indoor.get(), outdoor_transposed.get(), through_window.get(), rows,
                             cells, kTregenzaBinCount, rows / batches, tensor_cores));
      through = through_window.get();
      if (bins != kTregenzaBinCount) {
        FENESTRA_CUDA_RETURN_IF_ERROR(split_rows.Reserve(static_cast<size_t>(rows) * bins));
        SplitRowsKernel<<<rows, 2 * kTregenzaBinCount>>>(through, indoor.get(), cells,
                                                         split_rows.get());
        through = split_rows.get();
      }
    }
    Multiply(through, sky_matrix, illuminance.get(), rows, sky_steps, bins);
    FENESTRA_CUDA_RETURN_IF_ERROR(cudaGetLastError());
    return absl::OkStatus();
  }
  // Uploads design k's direct-sun entries sun[k] (and the design of each) to sun_entries
  // and sun_designs; returns their count. InvalidArgument for an entry outside `sensors` x
  // `sky_steps`.
  absl::StatusOr<int> UploadSun(const SunEntries* sun, int designs, int sensors, int sky_steps) {
    std::vector<SunEntry> entries;
    std::vector<int> design_of;
    for (int k = 0; k < designs; ++k) {
      for (size_t i = 0; i < sun[k].count; ++i) {
        const SunEntry& e = sun[k].entries[i];
        if (e.sensor < 0 || e.sensor >= sensors || e.column < 0 || e.column >= sky_steps) {
          return absl::InvalidArgumentError("CUDA annual product: a direct-sun entry out of range");
        }
        entries.push_back(e);
        design_of.push_back(k);
      }
    }
    if (entries.empty()) return 0;
    FENESTRA_CUDA_RETURN_IF_ERROR(sun_entries.Upload(entries.data(), entries.size()));
    FENESTRA_CUDA_RETURN_IF_ERROR(sun_designs.Upload(design_of.data(), design_of.size()));
    return static_cast<int>(entries.size());
  }
  // Adds design k's direct-sun entries sun[k] to its E (`designs` designs' rows as the
  // tallies lay them out) in every batch.
  absl::Status AddSun(const SunEntries* sun, int designs, int batches, int sensors, int sky_steps) {
    FENESTRA_ASSIGN_OR_RETURN(count, UploadSun(sun, designs, sensors, sky_steps));
    if (count == 0) return absl::OkStatus();
    if (bins != 2 * kTregenzaBinCount) {
      return absl::InvalidArgumentError("CUDA annual product: the direct sun needs a split sky");
    }
    const int threads = 256;
    AddSunKernel<<<(count + threads - 1) / threads, threads>>>(sun_entries.get(), sun_designs.get(),
                                                               count, designs, batches, sensors,
                                                               sky_steps, illuminance.get());
    FENESTRA_CUDA_RETURN_IF_ERROR(cudaGetLastError());
    return absl::OkStatus();
  }
  // The tallies of E from `indoor` (BatchMeanKernel's rows) for `designs` designs of `batches`
  // batches each, design k's into requests[k], its direct sun sun[k] added.
  absl::Status Tally(int designs, int batches, int sensors, const TallyRequest* requests,
                     const SunEntries* sun) {
    const int versions = batches + 1;
    const size_t per_sensor = static_cast<size_t>(versions) * sensors;
    FENESTRA_RETURN_IF_ERROR(FormIlluminance(designs * batches * sensors, batches));
    FENESTRA_RETURN_IF_ERROR(AddSun(sun, designs, batches, sensors, steps));
    static_assert(sizeof(double) == sizeof(unsigned long long));
    static_assert(sizeof(int64_t) == sizeof(unsigned long long));
    const TallyLayout layout{3 * per_sensor, 4 * static_cast<size_t>(versions),
                             5 * per_sensor + 4 * static_cast<size_t>(versions)};
    const size_t total = layout.total * designs;
    FENESTRA_CUDA_RETURN_IF_ERROR(tallies.Zero(total));
    const int threads = 256;
    const dim3 grid((steps + threads - 1) / threads, versions, designs);
    const TallyLimits limits{requests[0].lower_lux, requests[0].upper_lux, requests[0].da_lux,
                             static_cast<double>(batches), 1.0 / (batches - 1)};
    TallyKernel<<<grid, threads>>>(illuminance.get(), designs, batches, sensors, steps, limits,
                                   layout, tallies.get());
    FENESTRA_CUDA_RETURN_IF_ERROR(cudaGetLastError());
    host_tallies.resize(total);
    FENESTRA_CUDA_RETURN_IF_ERROR(tallies.Download(host_tallies.data(), total));
    for (int k = 0; k < designs; ++k) {
      const unsigned long long* design = host_tallies.data() + k * layout.total;
      std::memcpy(requests[k].counts, design, layout.counts * sizeof(int64_t));
      std::memcpy(requests[k].hours, design + layout.counts, layout.hours * sizeof(int64_t));
      std::memcpy(requests[k].sums, design + layout.counts + layout.hours,
                  2 * per_sensor * sizeof(double));
    }
    return absl::OkStatus();
  }
};

absl::Status CudaAnnualTally::SetGlare(const double* sun_factor, const uint8_t* occupied, int views,
                                       double threshold, double eye_limit) {
  Impl& d = *impl_;
  if (d.cells == 0) return NoProduct();
  if (views < 1) {
    return absl::InvalidArgumentError(absl::StrCat("CUDA glare: ", views, " views"));
  }
  FENESTRA_CUDA_RETURN_IF_ERROR(cudaSetDevice(d.device));
  FENESTRA_CUDA_RETURN_IF_ERROR(
      d.glare_factor.Upload(sun_factor, static_cast<size_t>(views) * d.steps));
  FENESTRA_CUDA_RETURN_IF_ERROR(d.glare_occupied.Upload(occupied, d.steps));
  // Done before it returns, as SetProduct
  FENESTRA_CUDA_RETURN_IF_ERROR(cudaStreamSynchronize(cudaStreamPerThread));
  d.glare_views = views;
  d.glare_steps = d.steps;
  d.glare_threshold = threshold;
  d.eye_limit = eye_limit;
  return absl::OkStatus();
}

absl::Status CudaAnnualTally::GlareSums(const double* device_sums, size_t design_sums, int designs,
                                        int batches, const uint64_t* batch_paths,
                                        const SunEntries* sun, int64_t* counts) {
  Impl& d = *impl_;
  FENESTRA_RETURN_IF_ERROR(CheckPairs(d.cells, batches));
  if (d.glare_views == 0 || d.glare_steps != d.steps) {
    return absl::FailedPreconditionError("CUDA glare: no glare tables for the product's steps");
  }
  if (designs < 1) {
    return absl::InvalidArgumentError(absl::StrCat("CUDA glare: ", designs, " designs"));
  }
  const int views = d.glare_views, versions = batches + 1;
  FENESTRA_RETURN_IF_ERROR(
      d.MeanOfSums(device_sums, design_sums, designs, batches, views, batch_paths));
  FENESTRA_RETURN_IF_ERROR(d.FormIlluminance(designs * batches * views, batches));
  FENESTRA_CUDA_RETURN_IF_ERROR(d.glare_sun.Zero(static_cast<size_t>(designs) * views * d.steps));
  FENESTRA_ASSIGN_OR_RETURN(entries, d.UploadSun(sun, designs, views, d.steps));
  const int threads = 256;
  if (entries > 0) {
    DenseSunKernel<<<(entries + threads - 1) / threads, threads>>>(
        d.sun_entries.get(), d.sun_designs.get(), entries, views, d.steps, d.glare_sun.get());
    FENESTRA_CUDA_RETURN_IF_ERROR(cudaGetLastError());
  }
  const size_t total = static_cast<size_t>(designs) * versions * (views + 1);
  FENESTRA_CUDA_RETURN_IF_ERROR(d.glare_counts.Zero(total));
  const GlareLimits limits{d.glare_threshold, d.eye_limit, 1.0 / batches, 1.0 / (batches - 1)};
  const dim3 grid((d.steps + threads - 1) / threads, versions, designs);
  GlareKernel<<<grid, threads>>>(d.illuminance.get(), d.glare_sun.get(), d.glare_factor.get(),
                                 d.glare_occupied.get(), designs, batches, views, d.steps, limits,
                                 d.glare_counts.get());
  FENESTRA_CUDA_RETURN_IF_ERROR(cudaGetLastError());
  d.host_glare_counts.resize(total);
  FENESTRA_CUDA_RETURN_IF_ERROR(d.glare_counts.Download(d.host_glare_counts.data(), total));
  static_assert(sizeof(int64_t) == sizeof(unsigned long long));
  std::memcpy(counts, d.host_glare_counts.data(), total * sizeof(int64_t));
  return absl::OkStatus();
}

CudaAnnualTally::CudaAnnualTally(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
CudaAnnualTally::~CudaAnnualTally() = default;

absl::StatusOr<std::unique_ptr<CudaAnnualTally>> CudaAnnualTally::Create(int device) {
  FENESTRA_RETURN_IF_ERROR(CheckCudaDevice(device));
  FENESTRA_CUDA_RETURN_IF_ERROR(cudaSetDevice(device));
  auto impl = std::make_unique<Impl>();
  impl->device = device;
  impl->tensor_cores = TensorCoresRun();
  return std::unique_ptr<CudaAnnualTally>(new CudaAnnualTally(std::move(impl)));
}

void CudaAnnualTally::UseTensorCores(bool use) {
  if (cudaSetDevice(impl_->device) == cudaSuccess) impl_->tensor_cores = use && TensorCoresRun();
}

bool CudaAnnualTally::UsesTensorCores() const { return impl_->tensor_cores; }

absl::Status CudaAnnualTally::SetProduct(const std::vector<const double*>& outdoor, int cells,
                                         const double* sky, int steps, int bins,
                                         bool outdoor_on_device) {
  Impl& d = *impl_;
  const int batches = static_cast<int>(outdoor.size());
  if (batches < 1 || batches > kMaxTallyBatches) {
    return absl::InvalidArgumentError(absl::StrCat(
        "CUDA annual product: ", batches, " outdoor batches, not 1 to ", kMaxTallyBatches));
  }
  // O_b as the host holds them, then transposed on the device (on the host, the transpose
  // took 50-60 ms of a four-variable job's second)
  const size_t batch_size = static_cast<size_t>(cells) * kTregenzaBinCount;
  const cudaMemcpyKind from = outdoor_on_device ? cudaMemcpyDeviceToDevice : cudaMemcpyHostToDevice;
  FENESTRA_CUDA_RETURN_IF_ERROR(cudaSetDevice(d.device));
  FENESTRA_CUDA_RETURN_IF_ERROR(d.outdoor_rows.Reserve(batch_size * batches));
  for (int b = 0; b < batches; ++b) {
    FENESTRA_CUDA_RETURN_IF_ERROR(cudaMemcpy(d.outdoor_rows.get() + b * batch_size, outdoor[b],
                                             batch_size * sizeof(double), from));
  }
  FENESTRA_CUDA_RETURN_IF_ERROR(d.outdoor_transposed.Reserve(batch_size * batches));
  const dim3 grid((kTregenzaBinCount + kTile - 1) / kTile, (cells + kTile - 1) / kTile, batches);
  TransposeKernel<<<grid, dim3(kTile, kTile)>>>(d.outdoor_rows.get(), d.outdoor_transposed.get(),
                                                cells, kTregenzaBinCount);
  FENESTRA_CUDA_RETURN_IF_ERROR(cudaGetLastError());
  FENESTRA_RETURN_IF_ERROR(CheckBins(bins));
  FENESTRA_CUDA_RETURN_IF_ERROR(d.sky.Upload(sky, static_cast<size_t>(bins) * steps));
  // Done before it returns (a pageable upload may return before its copy lands), so that
  // any host thread's stream may use the product
  FENESTRA_CUDA_RETURN_IF_ERROR(cudaStreamSynchronize(cudaStreamPerThread));
  d.bins = bins;
  d.cells = cells;
  d.steps = steps;
  d.outdoor_batches = batches;
  d.sky_only = false;
  return absl::OkStatus();
}

absl::Status CudaAnnualTally::SetSkyProduct(const double* sky, int steps, int bins) {
  Impl& d = *impl_;
  FENESTRA_RETURN_IF_ERROR(CheckBins(bins));
  FENESTRA_CUDA_RETURN_IF_ERROR(cudaSetDevice(d.device));
  FENESTRA_CUDA_RETURN_IF_ERROR(d.sky.Upload(sky, static_cast<size_t>(bins) * steps));
  // Done before it returns, as SetProduct
  FENESTRA_CUDA_RETURN_IF_ERROR(cudaStreamSynchronize(cudaStreamPerThread));
  d.bins = bins;
  d.cells = bins;
  d.steps = steps;
  d.outdoor_batches = 0;
  d.sky_only = true;
  return absl::OkStatus();
}

absl::Status CudaAnnualTally::Illuminance(const double* indoor, int rows, double* illuminance,
                                          const double* other_sky, int other_steps) {
  Impl& d = *impl_;
  if (d.cells == 0) return NoProduct();
  if (!d.sky_only && rows % d.outdoor_batches != 0) {
    return absl::InvalidArgumentError(absl::StrCat("CUDA annual product: ", rows,
                                                   " indoor rows do not split into ",
                                                   d.outdoor_batches, " batches"));
  }
  FENESTRA_RETURN_IF_ERROR(d.UploadIndoor(indoor, rows));
  return d.DownloadIlluminance(rows, d.sky_only ? 1 : d.outdoor_batches, illuminance, other_sky,
                               other_steps);
}

absl::Status CudaAnnualTally::Tally(const double* indoor, int batches, int sensors,
                                    const TallyRequest& request, SunEntries sun) {
  Impl& d = *impl_;
  FENESTRA_RETURN_IF_ERROR(CheckPairs(d.cells, batches));
  FENESTRA_RETURN_IF_ERROR(d.UploadIndoor(indoor, batches * sensors));
  return d.Tally(1, batches, sensors, &request, &sun);
}

absl::Status CudaAnnualTally::TallySums(const double* device_sums, size_t design_sums, int designs,
                                        int batches, int sensors, const uint64_t* batch_paths,
                                        const TallyRequest* requests, const SunEntries* sun) {
  Impl& d = *impl_;
  FENESTRA_RETURN_IF_ERROR(CheckPairs(d.cells, batches));
  if (designs < 1) {
    return absl::InvalidArgumentError(
        absl::StrCat("CUDA annual product: ", designs, " designs to tally"));
  }
  FENESTRA_RETURN_IF_ERROR(
      d.MeanOfSums(device_sums, design_sums, designs, batches, sensors, batch_paths));
  return d.Tally(designs, batches, sensors, requests, sun);
}

absl::Status CudaAnnualTally::IlluminanceOfSums(const double* device_sums, int batches, int sensors,
                                                const uint64_t* batch_paths,
                                                const double* other_sky, int other_steps,
                                                double* illuminance) {
  Impl& d = *impl_;
  FENESTRA_RETURN_IF_ERROR(CheckPairs(d.cells, batches));
  FENESTRA_RETURN_IF_ERROR(d.MeanOfSums(device_sums, 0, 1, batches, sensors, batch_paths));
  return d.DownloadIlluminance(batches * sensors, batches, illuminance, other_sky, other_steps);
}

absl::Status CudaAnnualTally::CheckPairs(int columns, int batches) const {
  const Impl& d = *impl_;
  if (d.cells == 0) return NoProduct();
  if (d.sky_only && columns == d.cells && batches >= 2 && batches <= kMaxTallyBatches)
    return absl::OkStatus();
  if (columns != d.cells || batches != d.outdoor_batches) {
    return absl::FailedPreconditionError(
        absl::StrCat("CUDA annual product: ", d.cells, " rows in ", d.outdoor_batches,
                     " batches, the indoor stage ", columns, " columns in ", batches));
  }
  return absl::OkStatus();
}

}  // namespace fenestra
