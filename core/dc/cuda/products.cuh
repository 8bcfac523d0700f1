#pragma once

// The dense products of the annual product on the GPU (annual_tally.cu): E = (I O) S as two
// products, I O on the FP64 tensor cores where the device has them. Host functions that
// launch their kernels on the calling thread's stream; the caller checks cudaGetLastError.
#include <cuda_runtime.h>

namespace fenestra {

// Whether the tensor-core kernel of MultiplyTransposed runs on the current device: its code
// there was built for compute capability 8.0 or later.
bool TensorCoresRun();

// C = A B_g^T for row-major A (m x k) and B_g (n x k), the rows of A in groups of group_rows
// with B_g each (the batches of the annual product, one after the other from b): C zeroed,
// then summed into; on the tensor cores where `tensor_cores` and n <= 256. n at most 1024.
cudaError_t MultiplyTransposed(const double* a, const double* b, double* c, int m, int k, int n,
                               int group_rows, bool tensor_cores);

// C = A B for row-major A (m x `bins`) and B (`bins` x n); bins kTregenzaBinCount or twice it
// (a split sky).
void Multiply(const double* a, const double* b, double* c, int m, int n, int bins);

}  // namespace fenestra
