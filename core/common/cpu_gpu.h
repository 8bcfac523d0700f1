#pragma once

// FENESTRA_CPU_GPU marks inline code that both the host compiler and nvcc compile.
// Such code uses PODs, fixed arrays and raw pointers only: no Eigen, std::vector,
// virtual calls, exceptions, logging or protobuf.
#if defined(__CUDACC__)
#define FENESTRA_CPU_GPU __host__ __device__
#else
#define FENESTRA_CPU_GPU
#endif

// FENESTRA_NOINLINE keeps a function out of its callers (rarely taken paths whose code
// would crowd the common one's registers).
#if defined(__CUDACC__)
#define FENESTRA_NOINLINE __noinline__
#else
#define FENESTRA_NOINLINE __attribute__((noinline))
#endif
