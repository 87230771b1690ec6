// Exclusive prefix sum of ints, in blocks of SCAN_BLOCK work-items (host/scan.cpp drives the
// levels). Integer sums are exact, so the result does not depend on the work-group size.
#define SCAN_BLOCK 256

// each work-group scans its block in local memory (Hillis-Steele) and writes the block total
// items at or past n_in read as zero, so scanning n_in + 1 items leaves the total at out[n_in]
__kernel void scan_blocks(__global const int* in, __global int* out, __global int* block_sums,
                          int n_in, int n_out) {
  __local int tmp[SCAN_BLOCK];
  int lid = get_local_id(0);
  int gid = get_global_id(0);
  int value = gid < n_in ? in[gid] : 0;
  tmp[lid] = value;
  barrier(CLK_LOCAL_MEM_FENCE);
  // inclusive scan by doubling offsets
  for (int offset = 1; offset < SCAN_BLOCK; offset <<= 1) {
    int add = lid >= offset ? tmp[lid - offset] : 0;
    barrier(CLK_LOCAL_MEM_FENCE);
    tmp[lid] += add;
    barrier(CLK_LOCAL_MEM_FENCE);
  }
  // exclusive result, and the block's total from the last item
  if (gid < n_out) out[gid] = tmp[lid] - value;
  if (lid == SCAN_BLOCK - 1) block_sums[get_group_id(0)] = tmp[lid];
}

// adds each block's scanned offset to its items
__kernel void scan_add_offsets(__global int* out, __global const int* block_offsets, int n) {
  int gid = get_global_id(0);
  if (gid < n) out[gid] += block_offsets[get_group_id(0)];
}
