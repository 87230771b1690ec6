// Graph colouring of contacts for parallel PGS: no dynamic body appears twice in a colour;
// static geometry never blocks. Jones-Plassmann rounds with fixed pseudo-random priorities:
// an uncoloured contact that outranks all its uncoloured neighbours takes the smallest colour
// its neighbours do not use. The result depends only on the contact list and the colours carried
// from last step's list (deterministic).
//
// A round reads the colours of earlier rounds (colour_in, -1 while uncoloured) and writes every
// contact's colour after it (colour_out; the host swaps the two), so no work-item reads what
// another writes in the same launch and the outcome does not depend on their order. Each round of
// a batch counts into its own pair of status words, status[2 slot] (contacts still uncoloured)
// and status[2 slot + 1] (contacts out of colours), which the host reads once per batch.

// Carried colours (issue 13): most of a step's contacts are last step's, and a colouring of
// last step's contacts, cut down to the pairs that persist, is still a colouring (the bodies are
// the same). So the colouring starts from last step's colours (carry_colours), keeps those below
// a cap that no neighbour of lower index shares (drop_colour_conflicts; the sharing is a guard,
// since the narrow phase could in principle find one pair twice), and the rounds below colour
// only the new contacts and those dropped.

// each contact's colour of last step, through the narrow phase's `previous` (-1 when new)
__kernel void carry_colours(__global const TlContact* contacts, int n_contacts,
                            __global const int* previous_colour, __global int* carried) {
  int c = get_global_id(0);
  if (c >= n_contacts) return;
  int k = contacts[c].previous;
  carried[c] = k >= 0 ? previous_colour[k] : -1;
}

// a carried colour stays if it is below `cap` (the colours of the last fresh colouring: the
// contacts above it are coloured again, which keeps the colours from spreading) and no neighbour
// of lower index carries the same one (reads `carried`, writes `colour`: the outcome does not
// depend on the work-items' order)
__kernel void drop_colour_conflicts(__global const TlContact* contacts, int n_contacts,
                                    __global const int* adj_offsets, __global const int* adjacency,
                                    __global const int* carried, int cap, __global int* colour) {
  int c = get_global_id(0);
  if (c >= n_contacts) return;
  int mine = carried[c] < cap ? carried[c] : -1;
  int bodies[2] = {contacts[c].a, contacts[c].b};
  for (int side = 0; side < 2 && mine >= 0; ++side) {
    int body = bodies[side];
    if (body < 0) continue;
    int end = adj_offsets[body + 1];
    for (int k = adj_offsets[body]; k < end; ++k) {
      int d = adjacency[k];
      if (d < c && carried[d] == mine) {
        mine = -1;
        break;
      }
    }
  }
  colour[c] = mine;
}

__kernel void colour_round(__global const TlContact* contacts, int n_contacts,
                           __global const int* adj_offsets, __global const int* adjacency,
                           __global const int* colour_in, __global int* colour_out,
                           __global int* status_words, int slot) {
  __global int* status = status_words + 2 * slot;
  int c = get_global_id(0);
  if (c >= n_contacts) return;
  int mine = colour_in[c];
  colour_out[c] = mine;  // coloured earlier, or uncoloured until shown otherwise below
  if (mine >= 0) return;
  uint priority = contact_priority((uint)c);
  ulong used = 0;
  int bodies[2] = {contacts[c].a, contacts[c].b};
  // scan the neighbours through both dynamic bodies
  for (int side = 0; side < 2; ++side) {
    int body = bodies[side];
    if (body < 0) continue;
    int end = adj_offsets[body + 1];
    for (int k = adj_offsets[body]; k < end; ++k) {
      int d = adjacency[k];
      if (d == c) continue;
      int cd = colour_in[d];
      if (cd < 0) {
        if (contact_priority((uint)d) > priority) {
          atomic_inc(&status[0]);  // still uncoloured after this round
          return;
        }
      } else {
        used |= 1ul << cd;
      }
    }
  }
  // smallest free colour
  int k = 0;
  while (k < TL_MAX_COLOURS && ((used >> k) & 1ul)) ++k;
  if (k == TL_MAX_COLOURS) {
    atomic_inc(&status[1]);  // overflow: reported by the host
    atomic_inc(&status[0]);
    return;
  }
  colour_out[c] = k;
}

// whether this step's contacts pair other bodies than the last step's, index for index: the
// adjacency and the colouring depend on nothing else, so where no pair differs (a bed at rest)
// the last step's colouring is this step's, bit for bit (solvers/dem_world.cpp begin_step).
// `differ` starts at 0; any work-item that finds a difference sets it
__kernel void contact_pairs_differ(__global const TlContact* now, __global const TlContact* before,
                                   int n_contacts, __global int* differ) {
  int c = get_global_id(0);
  if (c >= n_contacts) return;
  if (now[c].a != before[c].a || now[c].b != before[c].b) atomic_or(differ, 1);
}

// stable partition by colour, step 1: per block of COLOUR_BLOCK contacts, count each colour
#define COLOUR_BLOCK 256
__kernel void colour_histogram(__global const int* colour, int n_contacts, int blocks,
                               __global int* histogram) {
  int blk = get_global_id(0);
  if (blk >= blocks) return;
  int counts[TL_MAX_COLOURS];
  for (int k = 0; k < TL_MAX_COLOURS; ++k) counts[k] = 0;
  int end = min(n_contacts, (blk + 1) * COLOUR_BLOCK);
  for (int c = blk * COLOUR_BLOCK; c < end; ++c) {
    counts[colour[c]]++;
  }
  // colour-major layout, so one exclusive scan gives every (colour, block) start
  for (int k = 0; k < TL_MAX_COLOURS; ++k) histogram[k * blocks + blk] = counts[k];
}

// step 2 (after the scan): each block places its contacts in index order
__kernel void colour_scatter(__global const int* colour, int n_contacts, int blocks,
                             __global const int* histogram_offsets, __global int* order,
                             __global int* row_of_contact) {
  int blk = get_global_id(0);
  if (blk >= blocks) return;
  int next[TL_MAX_COLOURS];
  for (int k = 0; k < TL_MAX_COLOURS; ++k) next[k] = histogram_offsets[k * blocks + blk];
  int end = min(n_contacts, (blk + 1) * COLOUR_BLOCK);
  for (int c = blk * COLOUR_BLOCK; c < end; ++c) {
    int row = next[colour[c]]++;
    order[row] = c;
    row_of_contact[c] = row;
  }
}

// the first row of each colour (and the total at index TL_MAX_COLOURS)
__kernel void colour_ranges(__global const int* histogram_offsets, int blocks,
                            __global int* colour_start) {
  int k = get_global_id(0);
  if (k > TL_MAX_COLOURS) return;
  colour_start[k] = histogram_offsets[k * blocks];
}

// rows in contact order, one colour (the projected Jacobi sweep needs no colouring)
__kernel void identity_order(int n_contacts, __global int* order, __global int* row_of_contact) {
  int c = get_global_id(0);
  if (c >= n_contacts) return;
  order[c] = c;
  row_of_contact[c] = c;
}

// The row of the c-th of n contacts in the interleaved order of `lanes` blocks (interleaved_order,
// interleave_runs). Rows for a sweep that one work-item walks in turn (a CPU device's one-group
// sweep) need no colours: the contacts cut into `lanes` blocks of n/lanes or n/lanes + 1 in contact
// order (block j starts at floor(j n / lanes)), and the rows taking one contact of each block in
// turn. Rows next to each other then belong to blocks far apart in the grid's order and rarely
// share a body, so the core overlaps one row's arithmetic with the next's instead of waiting on the
// velocities the row before wrote (DemSettings::serial_lanes). Row of contact c at position p of
// block j: p lanes + j for p < n/lanes; the blocks of n/lanes + 1 (the first j of them number
// start_j - j (n/lanes)) give their last contacts the rows after those
int interleaved_row(int c, int n_contacts, int lanes) {
  // the last block starting at or before c: floor(j n / lanes) <= c  <=>  j <= ((c + 1) lanes - 1)
  // / n
  long n = n_contacts;
  int j = (int)min((long)(lanes - 1), ((long)(c + 1) * lanes - 1) / n);
  int start = (int)((long)j * n / lanes);
  int p = c - start;
  int q = n_contacts / lanes;
  return p < q ? p * lanes + j : q * lanes + (start - j * q);
}

// a whole system's rows interleaved (one work-item walks them)
__kernel void interleaved_order(int n_contacts, int lanes, __global int* order,
                                __global int* row_of_contact) {
  int c = get_global_id(0);
  if (c >= n_contacts) return;
  int row = interleaved_row(c, n_contacts, lanes);
  order[row] = c;
  row_of_contact[c] = row;
}

// Runs (issue 13): a large system on a CPU device is swept as runs of rows, each walked by one
// work-item of its own work-group, a level's runs side by side on the cores, the levels in turn
// (solvers/pgs_sweep.cpp). Particle i belongs to part floor(i parts / particles); a contact to the
// run of its dynamic bodies' parts (kernels/dem_types.h tl_run_of: its part's, or for one across
// parts the smallest aligned group's that holds both). Two runs of a level share no dynamic body,
// so their walks never race and the result is that of one walk over all runs in turn, bit for bit.
// The piles emit particles layer by layer and the grains of a dig stay near their neighbours, so
// index ranges are regions of the pile and few contacts cross them (bench/RESULTS.md 2026-12-02,
// "runs")
__kernel void contact_part(__global const TlContact* contacts, int n_contacts, int particles,
                           int parts, __global int* run) {
  int c = get_global_id(0);
  if (c >= n_contacts) return;
  int pa = (int)((long)contacts[c].a * parts / particles);
  int b = contacts[c].b;
  int pb = b >= 0 ? (int)((long)b * parts / particles) : pa;
  run[c] = tl_run_of(pa, pb, parts);
}

// the rows of each run (laid out run after run by the stable partition, `by_part`; the runs'
// first rows in part_start, `runs` + 1 entries) interleaved within their run as interleaved_order
// lays out a whole system
__kernel void interleave_runs(__global const int* by_part, __global const int* part_start, int runs,
                              int n_contacts, int lanes, __global int* order,
                              __global int* row_of_contact) {
  int i = get_global_id(0);
  if (i >= n_contacts) return;
  int k = 0;
  while (k + 1 < runs && part_start[k + 1] <= i) ++k;
  int begin = part_start[k];
  int row = begin + interleaved_row(i - begin, part_start[k + 1] - begin, lanes);
  int c = by_part[i];
  order[row] = c;
  row_of_contact[c] = row;
}
