#include "solvers/bucket_rows.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <map>
#include <string>

#include "host/error.hpp"
#include "solvers/contact_law.hpp"
#include "solvers/contact_sweep.hpp"
#include "solvers/dem_world.hpp"

namespace talus {

namespace {

// a previous contact of the same particle is the same contact when the normals agree this well
// (cos 37 degrees): features of one bucket are at least 45 degrees apart (bottom/back/sides)
constexpr double kSameNormal = 0.8;

// [r]x, the cross-product matrix: skew(r) p = r x p
Mat3d skew(const Vec3& r) {
  Mat3d s;
  s << 0.0, -r.z(), r.y(), r.z(), 0.0, -r.x(), -r.y(), r.x(), 0.0;
  return s;
}

// the largest eigenvalue of a symmetric (positive semi-definite) 3x3 block
double largest_eigenvalue(const Mat3d& m) {
  Eigen::SelfAdjointEigenSolver<Mat3d> es(0.5 * (m + m.transpose()), Eigen::EigenvaluesOnly);
  return std::max(0.0, es.eigenvalues().maxCoeff());
}

// the bucket's twist change from impulse p at arm r plus angular impulse l
void add_twist_change(BucketBody& b, const Vec3& p, const Vec3& l) {
  Vec6 w;
  w << p, l;
  const Vec6 d = b.mobility * w;
  b.velocity += d.head<3>();
  b.omega += d.tail<3>();
}

}  // namespace

std::vector<int> match_bucket_contacts(const std::vector<BucketContact>& contacts,
                                       const std::vector<BucketImpulse>& previous) {
  std::vector<int> match(contacts.size(), -1);
  std::vector<char> used(previous.size(), 0);
  for (size_t k = 0; k < contacts.size(); ++k) {
    // the previous contacts of this particle (a sorted range)
    const int particle = contacts[k].particle;
    auto lo = std::lower_bound(previous.begin(), previous.end(), particle,
                               [](const BucketImpulse& p, int i) { return p.particle < i; });
    double best = kSameNormal;
    for (auto it = lo; it != previous.end() && it->particle == particle; ++it) {
      const size_t j = static_cast<size_t>(it - previous.begin());
      const double c = it->normal.dot(contacts[k].normal);
      if (!used[j] && c > best) {
        best = c;
        match[k] = static_cast<int>(j);
      }
    }
    if (match[k] >= 0) used[match[k]] = 1;
  }
  return match;
}

std::vector<ContactRow> make_bucket_rows(const std::vector<BucketContact>& contacts,
                                             const Particles& particles, const BucketBody& bucket,
                                             const Vec3& com, const StepParams& p,
                                             const BucketMaterial& material,
                                             const std::vector<BucketImpulse>& previous,
                                             const std::vector<int>& match) {
  std::vector<ContactRow> rows;
  rows.reserve(contacts.size());
  const double h = p.dt;
  const double upsilon = 1.0 / (1.0 + 4.0 * p.damping_tau / h);
  for (size_t k = 0; k < contacts.size(); ++k) {
    const BucketContact& c = contacts[k];
    const int a = c.particle;
    const Vec3& n = c.normal;
    const double r = particles.radius[a];
    const Vec3 arm_b = c.point - com;

    // normal velocity before the step, predicted overlap, SPOOK with secant Hertz compliance
    const Vec3 v_point = bucket.velocity + bucket.omega.cross(arm_b);
    const double un = n.dot(v_point - particles.velocity[a]);
    const double stiffness = hertz_stiffness(r, p);
    const double overlap = std::max(std::max(-c.gap, -c.gap - h * un), p.overlap_floor_rel * r);
    const double compliance = 1.0 / (stiffness * std::sqrt(overlap));
    const double sigma = 4.0 * compliance * upsilon / (h * h);

    ContactRow row;
    row.normal = n;
    row.rhs = -(4.0 / h) * upsilon * c.gap + upsilon * un;
    row.arm_a = c.arm_particle;
    row.arm_b = arm_b;
    row.sigma = sigma;
    row.friction = material.friction;
    row.rolling_limit = material.rolling * r;
    row.a = a;
    row.b = TL_BUCKET_BODY;
    row.contact = static_cast<int>(k);

    // warm start: the matched impulses carried into the new frame, within the new cones
    const int j = k < match.size() ? match[k] : -1;
    if (j >= 0) {
      const BucketImpulse& old = previous[j];
      const double ln = old.impulse_n;
      const Vec3 projected = old.impulse_t - old.impulse_t.dot(n) * n;
      const double pm = projected.norm();
      row.impulse_n = ln;
      row.impulse_t = pm > 0.0 ? Vec3(projected * (std::min(old.impulse_t.norm(), row.friction * ln) / pm))
                               : Vec3::Zero();
      const double rmax = row.rolling_limit * ln;
      const double twist = std::clamp(old.impulse_r.dot(n), -rmax, rmax);
      Vec3 roll = old.impulse_r - old.impulse_r.dot(n) * n;
      if (roll.norm() > rmax) roll *= rmax / roll.norm();
      row.impulse_r = roll + twist * n;
    }
    rows.push_back(row);
  }
  set_bucket_effective_masses(rows, contacts, particles, bucket.mobility);
  return rows;
}

const char* bucket_sweep_name(BucketSweep sweep) {
  return sweep == BucketSweep::Coloured ? "coloured" : "serial";
}

BucketSweep parse_bucket_sweep(const std::string& text, const std::string& field) {
  if (text == "serial") return BucketSweep::Serial;
  if (text == "coloured") return BucketSweep::Coloured;
  throw InputError(field + ": unknown bucket sweep '" + text + "'; use 'serial' or 'coloured'");
}

BucketColouring colour_bucket_rows(const std::vector<int>& particle_of_row) {
  // each row's colour: how many rows of its particle came before it
  std::map<int, int> seen;
  std::vector<int> colour(particle_of_row.size());
  int colours = 0;
  for (size_t k = 0; k < particle_of_row.size(); ++k) {
    colour[k] = seen[particle_of_row[k]]++;
    colours = std::max(colours, colour[k] + 1);
  }
  // the rows by colour, in row order within one (a counting sort)
  BucketColouring out;
  out.colour_start.assign(colours + 1, 0);
  for (int c : colour) ++out.colour_start[c + 1];
  for (int c = 0; c < colours; ++c) out.colour_start[c + 1] += out.colour_start[c];
  std::vector<int> next(out.colour_start.begin(), out.colour_start.end() - 1);
  out.order.resize(particle_of_row.size());
  out.split.resize(particle_of_row.size());
  for (size_t k = 0; k < colour.size(); ++k) {
    out.order[next[colour[k]]++] = static_cast<int>(k);
    out.split[k] = out.colour_start[colour[k] + 1] - out.colour_start[colour[k]];
  }
  return out;
}

void set_bucket_effective_masses(std::vector<ContactRow>& rows,
                                 const std::vector<BucketContact>& contacts,
                                 const Particles& particles, const Mat6& mobility,
                                 const std::vector<int>& split) {
  if (!split.empty() && split.size() != rows.size())
    throw Error("set_bucket_effective_masses: " + std::to_string(split.size()) +
                " split factors for " + std::to_string(rows.size()) + " rows");
  const double d_r_bucket = largest_eigenvalue(mobility.block<3, 3>(3, 3));
  for (size_t k = 0; k < rows.size(); ++k) {
    ContactRow& row = rows[k];
    // the bucket as this row sees it: shared s ways in the coloured sweep (mobility s W)
    const double s = split.empty() ? 1.0 : split[k];
    const BucketContact& c = contacts.at(row.contact);
    const Vec3& n = row.normal;
    const double inv_m = particles.inv_mass[row.a];
    const double inv_i = particles.inv_inertia[row.a];
    // the bucket's point mobility at the contact: K_b = E W E^T, E = [I, -[arm]x]
    Eigen::Matrix<double, 3, 6> E;
    E << Mat3d::Identity(), -skew(row.arm_b);
    Mat3d K = E * mobility * E.transpose();
    if (!split.empty()) K *= s;
    // effective masses: exact along n, an upper bound across (see the header)
    const Mat3d across = Mat3d::Identity() - n * n.transpose();
    const double d_n = inv_m + n.dot(K * n) + row.sigma;
    const double d_t = inv_m + inv_i * c.arm_particle.squaredNorm() + largest_eigenvalue(across * K * across);
    const double d_r = inv_i + (split.empty() ? d_r_bucket : s * d_r_bucket);
    row.inv_dn = 1.0 / d_n;
    row.inv_dt = d_t > 0.0 ? 1.0 / d_t : 0.0;
    row.inv_dr = d_r > 0.0 ? 1.0 / d_r : 0.0;
  }
}

Vec6 bucket_wrench_impulse(const std::vector<ContactRow>& rows) {
  Vec6 j = Vec6::Zero();
  for (const auto& r : rows) {
    const Vec3 P = r.impulse_n * r.normal + r.impulse_t;
    j.head<3>() += P;
    j.tail<3>() += r.arm_b.cross(P) + r.impulse_r;
  }
  return j;
}

std::vector<BucketImpulse> bucket_impulses(const std::vector<ContactRow>& rows,
                                           const std::vector<int>& particle_index) {
  std::vector<BucketImpulse> out;
  out.reserve(rows.size());
  for (const auto& r : rows) {
    BucketImpulse b;
    b.particle = particle_index.at(r.a);
    b.normal = r.normal;
    b.impulse_n = r.impulse_n;
    b.impulse_t = r.impulse_t;
    b.impulse_r = r.impulse_r;
    out.push_back(b);
  }
  return out;
}

TlBucketBody to_device(const BucketBody& b) {
  TlBucketBody d{};
  d.velocity = to_float4(b.velocity, 0.0);
  d.omega = to_float4(b.omega, 0.0);
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) d.mobility[6 * i + j] = static_cast<float>(b.mobility(i, j));
  return d;
}

BucketBody from_device(const TlBucketBody& d) {
  BucketBody b;
  b.velocity = xyz(d.velocity);
  b.omega = xyz(d.omega);
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) b.mobility(i, j) = d.mobility[6 * i + j];
  return b;
}

void write_bucket_impulses(ByteWriter& w, const std::vector<BucketImpulse>& impulses) {
  w.u64(impulses.size());
  for (const BucketImpulse& b : impulses) {
    w.i64(b.particle);
    write_matrix(w, b.normal);
    w.f64(b.impulse_n);
    write_matrix(w, b.impulse_t);
    write_matrix(w, b.impulse_r);
  }
}

std::vector<BucketImpulse> read_bucket_impulses(ByteReader& r, size_t particles) {
  // what write_bucket_impulses writes per impulse: the particle index, the normal, the normal
  // impulse, the friction and rolling impulses
  constexpr std::uint64_t kImpulseBytes = 8 * (1 + 3 + 1 + 3 + 3);
  const std::uint64_t n = r.u64("bucket impulses");
  r.need_elements(n, kImpulseBytes, "bucket impulses");
  std::vector<BucketImpulse> impulses(n);
  for (BucketImpulse& b : impulses) {
    const std::int64_t particle = r.i64("bucket impulses");
    if (particle < 0 || particle >= static_cast<std::int64_t>(particles))
      throw InputError(r.where() + ": a bucket contact with particle " + std::to_string(particle) +
                       " of " + std::to_string(particles) + " (corrupt)");
    b.particle = static_cast<int>(particle);
    read_matrix(r, b.normal, "bucket impulses");
    b.impulse_n = r.f64("bucket impulses");
    read_matrix(r, b.impulse_t, "bucket impulses");
    read_matrix(r, b.impulse_r, "bucket impulses");
  }
  return impulses;
}

namespace reference {

namespace {

// one row's starting impulses on its particle (kernels/bucket.cl bucket_row_warm_start)
void warm_start_bucket_row(const ContactRow& row, Particles& particles) {
  const int a = row.a;
  const Vec3 P = row.impulse_n * row.normal + row.impulse_t;
  particles.velocity[a] -= particles.inv_mass[a] * P;
  particles.omega[a] -= particles.inv_inertia[a] * (row.arm_a.cross(P) + row.impulse_r);
}

// one row against the bucket (kernels/bucket.cl bucket_row_solve): normal, friction, rolling,
// the bucket moved through its mobility by every impulse change
void solve_bucket_row(ContactRow& row, Particles& particles, BucketBody& bucket) {
  const int a = row.a;
  Vec3& va = particles.velocity[a];
  Vec3& wa = particles.omega[a];
  const double ima = particles.inv_mass[a];
  const double iia = particles.inv_inertia[a];
  const Vec3& n = row.normal;
  double ln = row.impulse_n;

  // normal
  const double un = n.dot(bucket.velocity + bucket.omega.cross(row.arm_b) - va);
  const double ln_new = contact_law::normal_impulse(ln, row.rhs, un, row.sigma, row.inv_dn, 0.0);
  const Vec3 dp = (ln_new - ln) * n;
  va -= ima * dp;
  add_twist_change(bucket, dp, row.arm_b.cross(dp));
  ln = ln_new;

  // friction on the disc
  const Vec3 u = (bucket.velocity + bucket.omega.cross(row.arm_b)) - (va + wa.cross(row.arm_a));
  const Vec3 ut = u - u.dot(n) * n;
  const Vec3 lt_new =
      contact_law::friction_impulse(row.impulse_t, ut, row.inv_dt, row.friction * ln);
  const Vec3 dlt = lt_new - row.impulse_t;
  va -= ima * dlt;
  wa -= iia * row.arm_a.cross(dlt);
  add_twist_change(bucket, dlt, row.arm_b.cross(dlt));

  // rolling and twist
  const Vec3 wrel = bucket.omega - wa;
  const Vec3& lr = row.impulse_r;
  const Vec3 lr_new = contact_law::rolling_impulse(lr, wrel, n, row.inv_dr, row.rolling_limit * ln);
  const Vec3 dlr = lr_new - lr;
  wa -= iia * dlr;
  add_twist_change(bucket, Vec3::Zero(), dlr);

  row.impulse_n = ln;
  row.impulse_t = lt_new;
  row.impulse_r = lr_new;
}

}  // namespace

void bucket_warm_start(const std::vector<ContactRow>& rows, Particles& particles) {
  for (const ContactRow& row : rows) warm_start_bucket_row(row, particles);
}

void bucket_sweep(std::vector<ContactRow>& rows, Particles& particles, BucketBody& bucket) {
  for (ContactRow& row : rows) solve_bucket_row(row, particles, bucket);
}

void bucket_warm_start_coloured(const std::vector<ContactRow>& rows,
                                const BucketColouring& colouring, Particles& particles) {
  // a particle's rows in colour order
  for (int k : colouring.order) warm_start_bucket_row(rows.at(k), particles);
}

void bucket_sweep_coloured(std::vector<ContactRow>& rows, const BucketColouring& colouring,
                           Particles& particles, BucketBody& bucket) {
  for (size_t c = 0; c + 1 < colouring.colour_start.size(); ++c) {
    const int begin = colouring.colour_start[c], end = colouring.colour_start[c + 1];
    // every row against its own copy of the bucket, split s ways
    const double s = end - begin;
    BucketBody copy = bucket;
    copy.mobility *= s;
    Vec6 moved = Vec6::Zero();
    for (int k = begin; k < end; ++k) {
      copy.velocity = bucket.velocity;
      copy.omega = bucket.omega;
      solve_bucket_row(rows.at(colouring.order[k]), particles, copy);
      moved += (copy.twist() - bucket.twist()) / s;
    }
    // the bucket by the mean of the copies' changes
    bucket.velocity += moved.head<3>();
    bucket.omega += moved.tail<3>();
  }
}

}  // namespace reference

namespace {

// the floats of a row's coupling in the sweep's local memory: G = W J_b^T (6x3) and G n
// (kernels/bucket.cl TL_COUPLING_FLOATS)
constexpr size_t kCouplingFloats = 24;

// the chunk's local memory, the last arguments of both chain kernels from `first` on
// (kernels/bucket.cl: rows, velocities, omegas, particle indices, slots; the sweep's rows'
// couplings too)
void set_chunk_args(cl::Kernel& kernel, cl_uint first, size_t chunk, bool coupling) {
  cl_checked("setting the bucket chunk's local memory", [&] {
    kernel.setArg(first, cl::Local(chunk * sizeof(TlRow)));
    kernel.setArg(first + 1, cl::Local(chunk * sizeof(cl_float4)));
    kernel.setArg(first + 2, cl::Local(chunk * sizeof(cl_float4)));
    kernel.setArg(first + 3, cl::Local(chunk * sizeof(cl_int)));
    if (coupling) kernel.setArg(first + 5, cl::Local(chunk * kCouplingFloats * sizeof(cl_float)));
    return kernel.setArg(first + 4, cl::Local(chunk * sizeof(cl_int)));
  });
}

}  // namespace

BucketRowBlock::BucketRowBlock(Device& dev, size_t chunk)
    : dev_(dev),
      rows_(dev, 1),
      colour_start_(dev, 1),
      body_(dev, 1),
      index_(dev, 1),
      gathered_position_(dev, 1),
      gathered_velocity_(dev, 1),
      gathered_omega_(dev, 1),
      chunk_(chunk > 0 ? chunk : (dev.is_gpu() ? kWorkGroupSize : 1)) {
  const cl::Program& program = dev.program(kSolverProgram);
  gather_kernel_ = dev.kernel(program, "bucket_gather");
  warm_kernel_ = dev.kernel(program, "bucket_warm_start");
  sweep_kernel_ = dev.kernel(program, "bucket_sweep");
  warm_coloured_kernel_ = dev.kernel(program, "bucket_warm_start_coloured");
  sweep_coloured_kernel_ = dev.kernel(program, "bucket_sweep_coloured");
  // the coloured sweep's one work-group must fit the device (its bits depend on the size, so it
  // is not shrunk to fit)
  for (cl::Kernel* k : {&warm_coloured_kernel_, &sweep_coloured_kernel_}) {
    const size_t most = cl_checked("querying the coloured bucket sweep's work-group size", [&] {
      return k->getWorkGroupInfo<CL_KERNEL_WORK_GROUP_SIZE>(dev.device());
    });
    if (most < kColouredGroup)
      throw Error("the coloured bucket sweep needs work-groups of " +
                  std::to_string(kColouredGroup) +
                  " work-items; this device runs its kernels in at most " + std::to_string(most) +
                  ": use the serial bucket sweep (--bucket-sweep serial) on it");
  }
}

Particles BucketRowBlock::gather(const std::vector<int>& index, const Buffer<cl_float4>& position,
                                 const Buffer<cl_float4>& velocity, const Buffer<cl_float4>& omega) {
  const size_t n = index.size();
  if (n == 0) return Particles{};
  index_.upload(index);
  gathered_position_.resize(n);
  gathered_velocity_.resize(n);
  gathered_omega_.resize(n);
  set_args(gather_kernel_, index_, static_cast<int>(n), position, velocity, omega, gathered_position_,
           gathered_velocity_, gathered_omega_);
  launch(dev_, gather_kernel_, n, "bucket_gather");
  // orientations are not gathered: the rows do not need them
  const std::vector<cl_float4> identity(n, to_float4(Vec3::Zero(), 1.0));
  // the three arrays read behind one wait
  std::vector<cl_float4> x, v, w;
  PendingReads reads(dev_);
  gathered_position_.enqueue_download(x, n);
  gathered_velocity_.enqueue_download(v, n);
  gathered_omega_.enqueue_download(w, n);
  reads.wait();
  return particles_from_device(x, v, w, identity);
}

void BucketRowBlock::set_rows(const std::vector<TlRow>& rows, const BucketColouring& colouring) {
  rows_count_ = static_cast<int>(rows.size());
  order_.clear();
  colours_ = 0;
  if (rows.empty()) return;
  if (colouring.empty()) {
    rows_.upload(rows);
    return;
  }
  if (colouring.order.size() != rows.size())
    throw Error("BucketRowBlock::set_rows: a colouring of " +
                std::to_string(colouring.order.size()) + " rows for " +
                std::to_string(rows.size()));
  // the rows in colour order on the device
  order_ = colouring.order;
  std::vector<TlRow> ordered;
  ordered.reserve(rows.size());
  for (int k : order_) ordered.push_back(rows[k]);
  rows_.upload(ordered);
  colour_start_.upload(colouring.colour_start);
  colours_ = static_cast<int>(colouring.colour_start.size()) - 1;
}

void BucketRowBlock::set_bucket(const BucketBody& bucket) { body_.upload({to_device(bucket)}); }

void BucketRowBlock::warm_start(Buffer<cl_float4>& velocity, Buffer<cl_float4>& omega) {
  if (rows_count_ == 0) return;
  if (!order_.empty()) {
    set_args(warm_coloured_kernel_, rows_, colour_start_, colours_, velocity, omega);
    launch_group(dev_, warm_coloured_kernel_, kColouredGroup, "bucket_warm_start_coloured");
    return;
  }
  set_args(warm_kernel_, rows_, rows_count_, velocity, omega);
  set_chunk_args(warm_kernel_, 4, chunk_, false);
  launch_group(dev_, warm_kernel_, chunk_, "bucket_warm_start");
}

void BucketRowBlock::sweep(Buffer<cl_float4>& velocity, Buffer<cl_float4>& omega) {
  if (rows_count_ == 0) return;
  if (!order_.empty()) {
    set_args(sweep_coloured_kernel_, rows_, colour_start_, colours_, velocity, omega, body_);
    cl_checked("setting the coloured bucket sweep's local memory", [&] {
      return sweep_coloured_kernel_.setArg(6, cl::Local(kColouredGroup * 6 * sizeof(cl_float)));
    });
    launch_group(dev_, sweep_coloured_kernel_, kColouredGroup, "bucket_sweep_coloured");
    return;
  }
  set_args(sweep_kernel_, rows_, rows_count_, velocity, omega, body_);
  set_chunk_args(sweep_kernel_, 5, chunk_, true);
  launch_group(dev_, sweep_kernel_, chunk_, "bucket_sweep");
}

std::vector<TlRow> BucketRowBlock::rows() const {
  if (rows_count_ == 0) return {};
  std::vector<TlRow> device = rows_.download(rows_count_);
  if (order_.empty()) return device;
  // back in the order they were given
  std::vector<TlRow> given(device.size());
  for (size_t k = 0; k < device.size(); ++k) given[order_[k]] = device[k];
  return given;
}

BucketBody BucketRowBlock::bucket() const { return from_device(body_.download(1)[0]); }

}  // namespace talus
