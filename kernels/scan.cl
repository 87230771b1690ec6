// Exclusive prefix sum of ints, in blocks of TL_SCAN_GROUP x TL_SCAN_ITEMS items (kernels/common.h;
// host/scan.cpp drives the levels). Integer sums are exact, so the result does not depend on the
// block size. Each work-item scans TL_SCAN_ITEMS items in sequence and the group scans the
// work-items' sums: eight items a work-item made the barriers of the group's scan (16 a block)
// an eighth as many per item, and the blocks an eighth as many, where a CPU device paid a loop
// over the group for each barrier (the G200 cell grid's scan, bench/RESULTS.md 2026-11-29).
#define SCAN_BLOCK_ITEMS (TL_SCAN_GROUP * TL_SCAN_ITEMS)
// a block's item i in local memory, one int of padding after every 32: a work-item's run of 8
// (stride 8 across the group) would otherwise meet in 4 of a GPU's 32 banks
#define SCAN_SLOT(i) ((i) + ((i) >> 5))

// each work-group scans its block in local memory and writes the block's total
// items at or past n_in read as zero, so scanning n_in + 1 items leaves the total at out[n_in]
__kernel void scan_blocks(__global const int* in, __global int* out, __global int* block_sums,
                          int n_in, int n_out) {
  __local int items[SCAN_SLOT(SCAN_BLOCK_ITEMS)];
  __local int sums[TL_SCAN_GROUP];
  int lid = get_local_id(0);
  int block = get_group_id(0) * SCAN_BLOCK_ITEMS;
  // the block into local memory, neighbouring work-items reading neighbouring items
  for (int k = 0; k < TL_SCAN_ITEMS; ++k) {
    int i = k * TL_SCAN_GROUP + lid;
    items[SCAN_SLOT(i)] = block + i < n_in ? in[block + i] : 0;
  }
  barrier(CLK_LOCAL_MEM_FENCE);
  // each work-item's run of TL_SCAN_ITEMS: its sum
  int first = lid * TL_SCAN_ITEMS;
  int own = 0;
  for (int k = 0; k < TL_SCAN_ITEMS; ++k) own += items[SCAN_SLOT(first + k)];
  sums[lid] = own;
  barrier(CLK_LOCAL_MEM_FENCE);
  // inclusive scan of the runs' sums by doubling offsets (Hillis-Steele)
  for (int offset = 1; offset < TL_SCAN_GROUP; offset <<= 1) {
    int add = lid >= offset ? sums[lid - offset] : 0;
    barrier(CLK_LOCAL_MEM_FENCE);
    sums[lid] += add;
    barrier(CLK_LOCAL_MEM_FENCE);
  }
  // the run's exclusive results in place, from the sum of the runs before it
  int running = sums[lid] - own;
  for (int k = 0; k < TL_SCAN_ITEMS; ++k) {
    int value = items[SCAN_SLOT(first + k)];
    items[SCAN_SLOT(first + k)] = running;
    running += value;
  }
  if (lid == TL_SCAN_GROUP - 1) block_sums[get_group_id(0)] = sums[lid];
  barrier(CLK_LOCAL_MEM_FENCE);
  // the block out, as it came in
  for (int k = 0; k < TL_SCAN_ITEMS; ++k) {
    int i = k * TL_SCAN_GROUP + lid;
    if (block + i < n_out) out[block + i] = items[SCAN_SLOT(i)];
  }
}

// adds each block's scanned offset to its items
__kernel void scan_add_offsets(__global int* out, __global const int* block_offsets, int n) {
  int block = get_group_id(0) * SCAN_BLOCK_ITEMS;
  int offset = block_offsets[get_group_id(0)];
  for (int k = 0; k < TL_SCAN_ITEMS; ++k) {
    int i = block + k * TL_SCAN_GROUP + get_local_id(0);
    if (i < n) out[i] += offset;
  }
}

// the whole scan by one work-item, item after item: what a CPU device runs for a short array
// (host/scan.cpp), where a group's 19 barriers over TL_SCAN_GROUP work-items cost more than the
// adds themselves (a G200 step's five scans of a few thousand items)
__kernel void scan_serial(__global const int* in, __global int* out, int n_in, int n_out) {
  if (get_global_id(0) != 0) return;
  int running = 0;
  for (int i = 0; i < n_out; ++i) {
    int value = i < n_in ? in[i] : 0;
    out[i] = running;
    running += value;
  }
}
