#pragma once

// FENESTRA_CPU_GPU marks inline code that both the host compiler and nvcc compile.
// Such code uses PODs, fixed arrays and raw pointers only: no Eigen, std::vector,
// virtual calls, exceptions, logging or protobuf.
#if defined(__CUDACC__)
#define FENESTRA_CPU_GPU __host__ __device__
#else
#define FENESTRA_CPU_GPU
#endif
