#pragma once

// Device and page-locked host allocations for the CUDA code (the tracer, the annual
// product), and how CUDA errors become the statuses those return. Compiled by nvcc only.
#include <cuda_runtime.h>

#include <algorithm>
#include <cstring>
#include <memory>
#include <string>

#include "absl/status/status.h"

namespace fenestra {

// A CUDA error as a status: out of memory is RESOURCE_EXHAUSTED, a missing device or driver
// UNAVAILABLE, anything else INTERNAL.
inline absl::Status CudaError(cudaError_t e) {
  const std::string message = std::string("CUDA: ") + cudaGetErrorString(e);
  switch (e) {
    case cudaSuccess:
      return absl::OkStatus();
    case cudaErrorMemoryAllocation:
      return absl::ResourceExhaustedError(message);
    case cudaErrorNoDevice:
    case cudaErrorInsufficientDriver:
    case cudaErrorDevicesUnavailable:
      return absl::UnavailableError(message);
    default:
      return absl::InternalError(message);
  }
}

// In a function returning an absl::Status: returns CudaError of `expr` (a cudaError_t) when it
// fails.
#define FENESTRA_CUDA_RETURN_IF_ERROR(expr)                                                     \
  do {                                                                                          \
    if (const cudaError_t fenestra_cuda_error_ = (expr); fenestra_cuda_error_ != cudaSuccess) { \
      return ::fenestra::CudaError(fenestra_cuda_error_);                                       \
    }                                                                                           \
  } while (0)

// OK where CUDA device `device` exists; UNAVAILABLE where the host has no device, otherwise
// INVALID_ARGUMENT naming how many there are.
inline absl::Status CheckCudaDevice(int device) {
  int count = 0;
  if (cudaGetDeviceCount(&count) != cudaSuccess) count = 0;
  if (count == 0) return absl::UnavailableError("no CUDA device is available on this host");
  if (device < 0 || device >= count) {
    return absl::InvalidArgumentError("CUDA device " + std::to_string(device) +
                                      " does not exist (" + std::to_string(count) + " visible)");
  }
  return absl::OkStatus();
}

// Where an allocation lives: device memory, or page-locked host memory.
struct DeviceMemory {
  static cudaError_t Allocate(void** data, size_t bytes) { return cudaMalloc(data, bytes); }
  static void Free(void* data) { cudaFree(data); }
};
struct PinnedMemory {
  static cudaError_t Allocate(void** data, size_t bytes) { return cudaMallocHost(data, bytes); }
  static void Free(void* data) { cudaFreeHost(data); }
};

// `T`s in `Memory`, freed on scope exit; grows on demand (without keeping its contents).
template <typename T, class Memory>
class Allocation {
 public:
  Allocation() = default;
  ~Allocation() {
    if (data_ != nullptr) Memory::Free(data_);
  }
  Allocation(const Allocation&) = delete;
  Allocation& operator=(const Allocation&) = delete;

  cudaError_t Reserve(size_t count) {
    count = std::max<size_t>(count, 1);
    if (count <= capacity_) return cudaSuccess;
    if (data_ != nullptr) Memory::Free(data_);
    data_ = nullptr;
    capacity_ = 0;
    const cudaError_t e = Memory::Allocate(reinterpret_cast<void**>(&data_), count * sizeof(T));
    if (e == cudaSuccess) capacity_ = count;
    return e;
  }
  T* get() const { return data_; }
  // The allocation, now the caller's to free (Memory::Free); this one is empty after.
  T* Release() {
    T* data = data_;
    data_ = nullptr;
    capacity_ = 0;
    return data;
  }

 private:
  T* data_ = nullptr;
  size_t capacity_ = 0;
};

// A device allocation with transfers from and to the host.
template <typename T>
class DeviceBuffer : public Allocation<T, DeviceMemory> {
 public:
  cudaError_t Upload(const T* host, size_t count) {
    const cudaError_t e = this->Reserve(count);
    if (e != cudaSuccess || count == 0) return e;
    return cudaMemcpy(this->get(), host, count * sizeof(T), cudaMemcpyHostToDevice);
  }
  cudaError_t Zero(size_t count) {
    const cudaError_t e = this->Reserve(count);
    if (e != cudaSuccess) return e;
    return cudaMemset(this->get(), 0, count * sizeof(T));
  }
  cudaError_t Download(T* host, size_t count) const {
    return cudaMemcpy(host, this->get(), count * sizeof(T), cudaMemcpyDeviceToHost);
  }
};

// Page-locked host memory for fast transfers of large results.
class PinnedBuffer : public Allocation<double, PinnedMemory> {
 public:
  // Device to host through this buffer.
  cudaError_t Download(const double* device, double* host, size_t count) {
    cudaError_t e = Reserve(count);
    if (e == cudaSuccess) {
      e = cudaMemcpy(get(), device, count * sizeof(double), cudaMemcpyDeviceToHost);
    }
    if (e == cudaSuccess) std::memcpy(host, get(), count * sizeof(double));
    return e;
  }
  // Host to device through this buffer.
  cudaError_t Upload(const double* host, double* device, size_t count) {
    cudaError_t e = Reserve(count);
    if (e != cudaSuccess) return e;
    std::memcpy(get(), host, count * sizeof(double));
    return cudaMemcpy(device, get(), count * sizeof(double), cudaMemcpyHostToDevice);
  }
};

// `buffer`'s device memory (on GPU `device`) handed to shared holders, the last of which
// frees it; `buffer` is empty after.
template <typename T>
std::shared_ptr<const T> HandOver(DeviceBuffer<T>& buffer, int device) {
  return std::shared_ptr<const T>(buffer.Release(), [device](const T* data) {
    int current = 0;
    const bool known = cudaGetDevice(&current) == cudaSuccess;
    if (cudaSetDevice(device) == cudaSuccess) cudaFree(const_cast<T*>(data));
    if (known) cudaSetDevice(current);
  });
}

}  // namespace fenestra
