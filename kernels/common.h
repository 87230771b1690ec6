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
#else
#include <CL/cl_platform.h>
typedef cl_float4 tl_float4;
typedef cl_float tl_float;
typedef cl_int tl_int;
typedef cl_uint tl_uint;
typedef cl_ulong tl_ulong;
#endif

#endif
