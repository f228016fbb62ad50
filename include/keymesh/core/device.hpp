#pragma once
// KEYMESH_HD marks functions compiled for both the CPU and, under nvcc, the
// GPU: the generators' per-element functors are written once and shared by
// the backends (src/generate on the CPU, src/cuda on NVIDIA GPUs).
#if defined(__CUDACC__)
#define KEYMESH_HD __host__ __device__
#else
#define KEYMESH_HD
#endif
