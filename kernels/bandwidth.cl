// Memory bandwidth probes for the roofline in bench/RESULTS.md (bench/memory_bandwidth.cpp).

// copy: reads and writes one float4 per item (32 bytes moved)
__kernel void bandwidth_copy(__global const float4* in, __global float4* out, int n) {
  int i = get_global_id(0);
  if (i < n) out[i] = in[i];
}

// triad (STREAM): a = b + s c, reads two float4 and writes one (48 bytes moved)
__kernel void bandwidth_triad(__global float4* a, __global const float4* b,
                              __global const float4* c, float s, int n) {
  int i = get_global_id(0);
  if (i < n) a[i] = b[i] + s * c[i];
}
