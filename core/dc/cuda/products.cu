// The dense products of the annual product on the GPU (products.cuh).
#include "core/dc/cuda/products.cuh"

#include "core/trace/path.h"

namespace fenestra {
namespace {

// C = A B for row-major A (m x kTregenzaBinCount) and B (kTregenzaBinCount x n): the sky bins'
// light through the window times the sky, E = (I O) S. A block holds kRows rows of A in shared
// memory; each thread takes a column of B (the warp's loads coalesced) and forms that
// column's kRows entries of C, every entry of A read by the whole warp at once.
constexpr int kRows = 16, kMultiplyThreads = 128;
template <int k>
__global__ void MultiplyKernel(const double* a, const double* b, double* c, int m, int n) {
  __shared__ double a_rows[kRows * k];
  const int first_row = static_cast<int>(blockIdx.y) * kRows;
  const int rows = min(kRows, m - first_row);
  for (int e = static_cast<int>(threadIdx.x); e < kRows * k; e += blockDim.x) {
    a_rows[e] = e / k < rows ? a[static_cast<size_t>(first_row) * k + e] : 0.0;
  }
  __syncthreads();
  const int column = static_cast<int>(blockIdx.x * blockDim.x + threadIdx.x);
  if (column >= n) return;
  double sum[kRows] = {};
  // Unrolled, so that the loads of B go out together rather than one wait each
#pragma unroll 8
  for (int i = 0; i < k; ++i) {
    const double x = __ldg(b + static_cast<size_t>(i) * n + column);
#pragma unroll
    for (int r = 0; r < kRows; ++r) sum[r] += a_rows[r * k + i] * x;
  }
#pragma unroll
  for (int r = 0; r < kRows; ++r) {
    if (r < rows) c[static_cast<size_t>(first_row + r) * n + column] = sum[r];
  }
}

// C = A B_g^T for row-major A (m x k) and B_g (n x k): for a long k and a small C (indoor
// rows through the window cells). The rows of A come in groups of group_rows, group g with
// its own B_g (the batches of the annual product), one after the other from b. A block takes
// up to kGroupRows rows of a group and a part of k, the group's rows' part waiting in shared
// memory in chunks of kChunk; each thread takes a column of C (a row of B_g, read once per
// block) and adds that column's kRows entries over the block's part of k to C (zeroed
// before), every row of A read by the whole warp at once.
constexpr int kChunk = 64;
template <int kGroupRows>
__global__ void MultiplyTransposedKernel(const double* a, const double* b, double* c, int k, int n,
                                         int group_rows, int part) {
  __shared__ double a_chunk[kGroupRows][kChunk];
  const int group = static_cast<int>(blockIdx.z);
  const int tile_row = static_cast<int>(blockIdx.y) * kGroupRows;
  const int first_row = group * group_rows + tile_row;
  const int rows = min(kGroupRows, group_rows - tile_row);
  const int column = static_cast<int>(threadIdx.x);
  const double* b_row = b + (static_cast<size_t>(group) * n + min(column, n - 1)) * k;
  double sum[kGroupRows] = {};
  const int begin = static_cast<int>(blockIdx.x) * part, end = min(k, begin + part);
  for (int start = begin; start < end; start += kChunk) {
    const int width = min(kChunk, end - start);
    __syncthreads();
    for (int e = static_cast<int>(threadIdx.x); e < kGroupRows * kChunk; e += blockDim.x) {
      const int r = e / kChunk, i = e % kChunk;
      a_chunk[r][i] =
          r < rows && i < width ? a[static_cast<size_t>(first_row + r) * k + start + i] : 0.0;
    }
    __syncthreads();
#pragma unroll 8
    for (int i = 0; i < width; ++i) {
      const double x = __ldg(b_row + start + i);
#pragma unroll
      for (int r = 0; r < kGroupRows; ++r) sum[r] += a_chunk[r][i] * x;
    }
  }
  if (column >= n) return;
#pragma unroll
  for (int r = 0; r < kGroupRows; ++r) {
    if (r < rows) atomicAdd(&c[static_cast<size_t>(first_row + r) * n + column], sum[r]);
  }
}

// The parts of k per group of MultiplyTransposedKernel: enough blocks to fill the device.
constexpr int kPartsPerGroup = 32;

// MultiplyTransposedKernel on the FP64 tensor cores (mma.sync m8n8k4, compute capability 8.0
// and later). A block takes up to kMmaRows rows of a group (four 8-row tiles) and a part of
// k, the rows' part waiting in shared memory in chunks of kMmaChunk (rows padded so that a
// warp's reads of eight rows fall in different banks); each warp forms an 8-column tile of C
// (8 rows of B_g, whose chunk it loads into registers at once) and adds it to C (zeroed
// before). Per lane, as the instruction lays out its operands: A's row lane / 4 and k
// lane % 4, B's column lane / 4 and k lane % 4, C's row lane / 4 and columns 2 (lane % 4)
// and the one after.
constexpr int kMmaRows = 32, kMmaChunk = 64, kMmaStride = kMmaChunk + 4, kMmaParts = 16;
constexpr int kMmaMaxColumns = 256;  // a warp per 8 columns, 32 warps at most
__global__ void MultiplyTransposedMmaKernel(const double* a, const double* b, double* c, int k,
                                            int n, int group_rows, int part) {
#if defined(__CUDA_ARCH__) && __CUDA_ARCH__ >= 800
  __shared__ double a_chunk[kMmaRows * kMmaStride];
  const int lane = static_cast<int>(threadIdx.x) % 32, warp = static_cast<int>(threadIdx.x) / 32;
  const int quad = lane / 4, step = lane % 4;
  const int group = static_cast<int>(blockIdx.z);
  const int tile_row = static_cast<int>(blockIdx.y) * kMmaRows;
  const int rows = min(kMmaRows, group_rows - tile_row), tiles = (rows + 7) / 8;
  const size_t first_row = static_cast<size_t>(group) * group_rows + tile_row;
  const int begin = static_cast<int>(blockIdx.x) * part, end = min(k, begin + part);
  const int b_column = 8 * warp + quad;
  const bool column_valid = b_column < n;
  const double* b_row = b + (static_cast<size_t>(group) * n + min(b_column, n - 1)) * k;
  double sum[kMmaRows / 8][2] = {};
  for (int start = begin; start < end; start += kMmaChunk) {
    const int width = min(kMmaChunk, end - start);
    __syncthreads();
    for (int e = static_cast<int>(threadIdx.x); e < kMmaRows * kMmaChunk; e += blockDim.x) {
      const int r = e / kMmaChunk, i = e % kMmaChunk;
      a_chunk[r * kMmaStride + i] =
          r < rows && i < width ? a[(first_row + r) * k + start + i] : 0.0;
    }
    __syncthreads();
    double x[kMmaChunk / 4];
#pragma unroll
    for (int s = 0; s < kMmaChunk / 4; ++s) {
      const int i = 4 * s + step;
      x[s] = column_valid && i < width ? __ldg(b_row + start + i) : 0.0;
    }
#pragma unroll
    for (int s = 0; s < kMmaChunk / 4; ++s) {
#pragma unroll
      for (int t = 0; t < kMmaRows / 8; ++t) {
        if (t >= tiles) break;  // the same for the whole block
        const double y = a_chunk[(8 * t + quad) * kMmaStride + 4 * s + step];
        asm("mma.sync.aligned.m8n8k4.row.col.f64.f64.f64.f64 {%0, %1}, {%2}, {%3}, {%0, %1};"
            : "+d"(sum[t][0]), "+d"(sum[t][1])
            : "d"(y), "d"(x[s]));
      }
    }
  }
#pragma unroll
  for (int t = 0; t < kMmaRows / 8; ++t) {
    const int row = 8 * t + quad;
    if (t >= tiles || row >= rows) continue;
    for (int v = 0; v < 2; ++v) {
      const int column = 8 * warp + 2 * step + v;
      if (column < n) atomicAdd(&c[(first_row + row) * n + column], sum[t][v]);
    }
  }
#endif
}

template <int kGroupRows>
void LaunchMultiplyTransposed(const double* a, const double* b, double* c, int k, int n,
                              int group_rows, int groups) {
  const int parts = min(kPartsPerGroup, (k + kChunk - 1) / kChunk);
  const int part = ((k + parts - 1) / parts + kChunk - 1) / kChunk * kChunk;
  const dim3 grid((k + part - 1) / part, (group_rows + kGroupRows - 1) / kGroupRows, groups);
  MultiplyTransposedKernel<kGroupRows>
      <<<grid, (n + 31) / 32 * 32>>>(a, b, c, k, n, group_rows, part);
}

}  // namespace

// Whether MultiplyTransposedMmaKernel runs on the current device: its code there was built
// for compute capability 8.0 or later.
bool TensorCoresRun() {
  cudaFuncAttributes attributes;
  return cudaFuncGetAttributes(&attributes, MultiplyTransposedMmaKernel) == cudaSuccess &&
         attributes.binaryVersion >= 80;
}

cudaError_t MultiplyTransposed(const double* a, const double* b, double* c, int m, int k, int n,
                               int group_rows, bool tensor_cores) {
  if (const cudaError_t e = cudaMemsetAsync(c, 0, static_cast<size_t>(m) * n * sizeof(double));
      e != cudaSuccess) {
    return e;
  }
  if (tensor_cores && n <= kMmaMaxColumns) {
    const int part = ((k + kMmaParts - 1) / kMmaParts + 3) / 4 * 4;
    const dim3 grid((k + part - 1) / part, (group_rows + kMmaRows - 1) / kMmaRows, m / group_rows);
    MultiplyTransposedMmaKernel<<<grid, 32 * ((n + 7) / 8)>>>(a, b, c, k, n, group_rows, part);
    return cudaGetLastError();
  }
  if (n > 1024) return cudaErrorInvalidValue;  // a thread per column of C
  // A block's rows: the fewest multiple of 4 up to 32 that holds a group (32 for more)
  using Launch = void (*)(const double*, const double*, double*, int, int, int, int);
  constexpr Launch kLaunches[] = {LaunchMultiplyTransposed<4>,  LaunchMultiplyTransposed<8>,
                                  LaunchMultiplyTransposed<12>, LaunchMultiplyTransposed<16>,
                                  LaunchMultiplyTransposed<20>, LaunchMultiplyTransposed<24>,
                                  LaunchMultiplyTransposed<28>, LaunchMultiplyTransposed<32>};
  kLaunches[(min(group_rows, 32) + 3) / 4 - 1](a, b, c, k, n, group_rows, m / group_rows);
  return cudaGetLastError();
}

// C = A B for A of m x `bins` (MultiplyKernel): the sky's bins, or a split sky's rows.
void Multiply(const double* a, const double* b, double* c, int m, int n, int bins) {
  const dim3 grid((n + kMultiplyThreads - 1) / kMultiplyThreads, (m + kRows - 1) / kRows);
  if (bins == 2 * kTregenzaBinCount) {
    MultiplyKernel<2 * kTregenzaBinCount><<<grid, kMultiplyThreads>>>(a, b, c, m, n);
  } else {
    MultiplyKernel<kTregenzaBinCount><<<grid, kMultiplyThreads>>>(a, b, c, m, n);
  }
}

}  // namespace fenestra
