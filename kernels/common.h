// Types shared by host C++ and OpenCL C. This file is prepended to every kernel program
// (host/device.cpp) and included by host code, so a layout is written down exactly once.
#ifndef TALUS_KERNELS_COMMON_H
#define TALUS_KERNELS_COMMON_H

#ifdef __OPENCL_VERSION__
typedef float4 tl_float4;
typedef float tl_float;
typedef int tl_int;
typedef uint tl_uint;
typedef ulong tl_ulong;
// a helper of the hot sweeps, inlined into its callers: PoCL otherwise keeps solve_contact and
// the contact law out of line and calls them once per work-item, which cost the D200 sweeps 11 %
// (262 against 295 ms per step, talus bench dem, bench/RESULTS.md 2026-11-24 issue 13)
#define TL_INLINE __attribute__((always_inline))
// a hint that a walk will soon read the cache line at p. On a CPU device (TL_CPU_DEVICE, set by
// host/device.cpp) it is the compiler's prefetch instruction, because PoCL compiles OpenCL's own
// prefetch() to nothing (checked in pgs_runs.so's disassembly, 2026-12-02); elsewhere nothing: a
// GPU hides a load's latency behind its other work-items
#if defined(TL_CPU_DEVICE) && defined(__clang__)
#define TL_PREFETCH(p) __builtin_prefetch((const __global void*)(p))
#else
#define TL_PREFETCH(p)
#endif
#else
#include <CL/cl_platform.h>
typedef cl_float4 tl_float4;
typedef cl_float tl_float;
typedef cl_int tl_int;
typedef cl_uint tl_uint;
typedef cl_ulong tl_ulong;
#endif

// the prefix sum's work-group size and the items each of its work-items scans in sequence
// (kernels/scan.cl, host/scan.cpp): a block is their product
#define TL_SCAN_GROUP 256
#define TL_SCAN_ITEMS 8

#endif
