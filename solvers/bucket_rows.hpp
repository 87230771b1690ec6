// Contact rows between particles and the bucket (SPEC §1 steps 3-6, issue 4).
//
// The bucket is one body of the vehicle. Particles see it through its articulated mobility W,
// the 6x6 Schur complement of the direct vehicle solve (vehicle::MultibodySystem::mobility): an
// impulse wrench [P; L] on the bucket changes its twist by W [P; L] with every joint, motor and
// tyre of the machine taking its share. The rows are the particle rows of kernels/solver.cl with
// body b the bucket:
//   - normal: SPOOK with the secant Hertz compliance of a sphere on a plate (R* = r, the same
//     material as walls), D_n = 1/m_a + n^T K_b n + Sigma with K_b = E W E^T the bucket's
//     point mobility at the contact (E maps a twist to the point's velocity);
//   - friction on the disc with the bucket-soil coefficient, rolling and twist as for walls.
//     Their effective masses are scalars: the particle's isotropic share plus the largest
//     eigenvalue of the bucket's tangential (or angular) block, an upper bound that keeps the
//     projected steps stable where the bucket's anisotropy would make an exact scalar wrong.
// Rows are made on the host in double (the contacts come from Embree on the host anyway) and
// solved on the device by kernels/bucket.cl; BucketRowBlock owns the device side. The free
// functions in namespace reference are the double twins of the kernels.
#pragma once
#include <string>
#include <vector>

#include "host/binary.hpp"
#include "host/device.hpp"
#include "kernels/common.h"
#include "kernels/dem_types.h"
#include "solvers/bucket_contacts.hpp"
#include "solvers/contact_rows.hpp"

namespace talus {

using Mat3d = Eigen::Matrix3d;
using Vec6 = vehicle::Vec6;
using Mat6 = vehicle::Mat6;

// the bucket as the rows see it: twist of its centre of mass and articulated mobility
struct BucketBody {
  Vec3 velocity = Vec3::Zero();  // [m/s]
  Vec3 omega = Vec3::Zero();     // [1/s]
  Mat6 mobility = Mat6::Zero();  // W: twist change per impulse wrench about the centre of mass
  Vec6 twist() const {
    Vec6 t;
    t << velocity, omega;
    return t;
  }
};

// the contact material between particles and the bucket
struct BucketMaterial {
  double friction = 0.2;  // bucket-soil Coulomb friction, paper §4.4 (calibrated there)
  double rolling = Material{}.rolling;  // rolling resistance against the plate: the gravel's own mu_r
};

// last step's solved impulses of one bucket contact, kept for warm starting
struct BucketImpulse {
  int particle = -1;
  Vec3 normal = Vec3::Zero();
  double impulse_n = 0.0;
  Vec3 impulse_t = Vec3::Zero();
  Vec3 impulse_r = Vec3::Zero();
};

// a saved state's list of bucket impulses (digging/saved_state): the particle index, the normal
// and the three impulses per contact. Reading refuses (InputError naming the reader's place) a
// particle index outside [0, particles)
void write_bucket_impulses(ByteWriter& w, const std::vector<BucketImpulse>& impulses);
std::vector<BucketImpulse> read_bucket_impulses(ByteReader& r, size_t particles);

// warm-start matching: for each new contact, the previous contact of the same particle whose
// normal is closest to the new one (and within 37 degrees, cos 0.8), each used at most once;
// -1 where none. `previous` sorted by particle (as rows are). A particle may touch the bucket at
// several features, so the particle alone is not a key; the triangle is not one either, since a
// particle sliding over the bottom plate crosses triangles every few steps.
std::vector<int> match_bucket_contacts(const std::vector<BucketContact>& contacts,
                                       const std::vector<BucketImpulse>& previous);

// the rows of the bucket contacts (double). `particles` holds the candidates' state before the
// step (velocities before gravity), indexed like contacts[k].particle; `com` is the bucket's
// centre of mass (arms are taken about it); `previous`/`match` give warm-start impulses (pass
// empty vectors for none). Each row's `a` is the particle's index in `particles`, b is
// TL_BUCKET_BODY, `contact` the contact's index.
std::vector<ContactRow> make_bucket_rows(const std::vector<BucketContact>& contacts,
                                             const Particles& particles, const BucketBody& bucket,
                                             const Vec3& com, const StepParams& p,
                                             const BucketMaterial& material,
                                             const std::vector<BucketImpulse>& previous,
                                             const std::vector<int>& match);

// how the bucket rows are swept inside every sweep (CouplingSettings::bucket_sweep; issue 13)
enum class BucketSweep {
  // one chain: every row after the one before it, the bucket moving with each (kernels/bucket.cl
  // bucket_sweep): true Gauss-Seidel for the bucket, one work-item's walk
  Serial,
  // colour by colour (colour_bucket_rows): a colour's rows at once, each against the bucket split
  // among them (mass splitting), the bucket moved by their mean after the colour
  // (bucket_sweep_coloured): a work-item a row, for devices where the chain's latency dominates
  Coloured,
};

// "serial" or "coloured"
const char* bucket_sweep_name(BucketSweep sweep);
// the inverse of bucket_sweep_name; throws InputError naming `field` otherwise
BucketSweep parse_bucket_sweep(const std::string& text, const std::string& field);

// the bucket rows' colours for BucketSweep::Coloured: colour c holds each particle's c-th row, so
// a colour's rows share no particle, and there are as many colours as the most rows a particle has
struct BucketColouring {
  std::vector<int> order;         // row indices, colour by colour, in row order within a colour
  std::vector<int> colour_start;  // colour c is order[colour_start[c] .. colour_start[c + 1])
  std::vector<int> split;         // split[k]: the size of row k's colour (rows sharing the bucket)
  bool empty() const { return order.empty(); }
};
// `particle_of_row[k]`: the particle of row k (any numbering, one number a particle)
BucketColouring colour_bucket_rows(const std::vector<int>& particle_of_row);

// the rows' effective masses (1/D of normal, friction and rolling) for the bucket's mobility W:
// the only part of a row that depends on W, so a coupled step can make its rows (and take their
// warm-start wrench) before the vehicle solve that gives W, then set these. `split` (one a row,
// BucketColouring::split; empty: all 1) makes row k see the bucket's mobility as split[k] W
void set_bucket_effective_masses(std::vector<ContactRow>& rows,
                                 const std::vector<BucketContact>& contacts,
                                 const Particles& particles, const Mat6& mobility,
                                 const std::vector<int>& split = {});

// the impulse wrench the rows put on the bucket about its centre of mass: sum of [P; arm x P + L]
Vec6 bucket_wrench_impulse(const std::vector<ContactRow>& rows);

// the rows' impulses for the next step's warm start; `particle_index` maps row.a to the
// particle's index in the whole system
std::vector<BucketImpulse> bucket_impulses(const std::vector<ContactRow>& rows,
                                           const std::vector<int>& particle_index);

TlBucketBody to_device(const BucketBody& b);
BucketBody from_device(const TlBucketBody& b);

namespace reference {
// kernels/bucket.cl bucket_warm_start: particles receive the rows' starting impulses
void bucket_warm_start(const std::vector<ContactRow>& rows, Particles& particles);
// kernels/bucket.cl bucket_sweep: one sweep over the rows in order, bucket through W
void bucket_sweep(std::vector<ContactRow>& rows, Particles& particles, BucketBody& bucket);
// kernels/bucket.cl bucket_warm_start_coloured and bucket_sweep_coloured: the rows (in their own
// order) colour by colour, each colour's rows against copies of the bucket with mobility s W
// (their effective masses made with that split), the bucket moved by the copies' mean change
void bucket_warm_start_coloured(const std::vector<ContactRow>& rows,
                                const BucketColouring& colouring, Particles& particles);
void bucket_sweep_coloured(std::vector<ContactRow>& rows, const BucketColouring& colouring,
                           Particles& particles, BucketBody& bucket);
}  // namespace reference

// the device side: rows, the bucket's state, and the gather of the candidates' state
class BucketRowBlock {
 public:
  // `chunk`: rows the serial sweep's work-group loads into local memory at a time (its work-group
  // size; the results do not depend on it, kernels/bucket.cl); 0 chooses by device: on a GPU the
  // launches' usual work-group size (chunk x 152 bytes of local memory: 9.7 kB at 64), on a CPU
  // 1, where the caches hide the loads and the chunks' barriers cost 14 % of the walk (PoCL,
  // HD27-D200: 6.4 against 5.6 ms a step, bench/RESULTS.md 2026-11-27 "chunked")
  // The coloured sweep's work-group is kColouredGroup work-items on every device (a power of two
  // for its tree sum; its bits depend on it)
  explicit BucketRowBlock(Device& dev, size_t chunk = 0);
  static constexpr size_t kColouredGroup = 64;
  static_assert((kColouredGroup & (kColouredGroup - 1)) == 0, "the tree sum halves the group");

  // the candidates' state (centre/radius, velocity/inverse mass, omega/inverse inertia) from the
  // particle buffers, in the order of `index`
  Particles gather(const std::vector<int>& index, const Buffer<cl_float4>& position,
                   const Buffer<cl_float4>& velocity, const Buffer<cl_float4>& omega);
  // rows with `a` already mapped to particle indices of the whole system. With a colouring
  // (colour_bucket_rows of these rows, their effective masses made with its split) the warm start
  // and the sweeps go colour by colour (BucketSweep::Coloured), else serially; rows() gives them
  // back in this order either way
  void set_rows(const std::vector<TlRow>& rows, const BucketColouring& colouring = {});
  void set_bucket(const BucketBody& bucket);
  int size() const { return rows_count_; }

  void warm_start(Buffer<cl_float4>& velocity, Buffer<cl_float4>& omega);
  void sweep(Buffer<cl_float4>& velocity, Buffer<cl_float4>& omega);
  std::vector<TlRow> rows() const;
  BucketBody bucket() const;

 private:
  Device& dev_;
  Buffer<TlRow> rows_;  // serial: the rows as given; coloured: in colour order
  Buffer<int> colour_start_;
  std::vector<int> order_;  // coloured: the given row of each device row; empty when serial
  int colours_ = 0;
  Buffer<TlBucketBody> body_;
  Buffer<int> index_;
  Buffer<cl_float4> gathered_position_, gathered_velocity_, gathered_omega_;
  int rows_count_ = 0;
  size_t chunk_;
  cl::Kernel gather_kernel_, warm_kernel_, sweep_kernel_, warm_coloured_kernel_,
      sweep_coloured_kernel_;
};

}  // namespace talus
