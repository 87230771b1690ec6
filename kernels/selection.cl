// Particles inside an axis-aligned box (the bucket's world bounds grown by the largest radius
// and the contact margin): a flag per particle, then a compaction at offsets from a prefix sum,
// so the selected indices come out in index order (solvers/bucket_selection.cpp).

__kernel void box_flags(__global const float4* position, int n, float4 lo, float4 hi,
                        __global int* flags) {
  int i = get_global_id(0);
  if (i >= n) return;
  float3 x = position[i].xyz;
  flags[i] = all(x >= lo.xyz) && all(x <= hi.xyz) ? 1 : 0;
}

__kernel void box_compact(__global const int* flags, __global const int* offsets, int n,
                          __global int* selected) {
  int i = get_global_id(0);
  if (i >= n || !flags[i]) return;
  selected[offsets[i]] = i;
}
