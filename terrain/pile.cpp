#include "terrain/pile.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>

#include "host/data_files.hpp"
#include "host/error.hpp"
#include "host/files.hpp"

namespace talus {

double PileProfile::height_at(double x) const {
  if (points.empty() || x < points.front().x() || x > rear_wall_x) return 0.0;
  for (size_t k = 1; k < points.size(); ++k) {
    const Vec3& p0 = points[k - 1];
    const Vec3& p1 = points[k];
    if (x <= p1.x()) {
      double s = p1.x() > p0.x() ? (x - p0.x()) / (p1.x() - p0.x()) : 1.0;
      return p0.z() + s * (p1.z() - p0.z());
    }
  }
  return points.back().z();
}

double PileProfile::cross_section() const {
  // trapezoids between profile points, then a flat top to the rear wall
  double area = 0.0;
  for (size_t k = 1; k < points.size(); ++k)
    area += 0.5 * (points[k].z() + points[k - 1].z()) * (points[k].x() - points[k - 1].x());
  if (!points.empty() && rear_wall_x > points.back().x())
    area += points.back().z() * (rear_wall_x - points.back().x());
  return area;
}

PileProfile load_pile_profile(const std::string& path) {
  const nlohmann::json j = read_json_file(path, "the pile profile");
  auto field = [&](const char* name) -> const nlohmann::json& {
    if (!j.contains(name))
      throw InputError(path + ": missing field '" + name + "'; see data/piles/default.json");
    return j.at(name);
  };
  PileProfile p;
  p.path = path;
  // the optional texts: a name for messages and plots, the profile's source
  auto text = [&](const char* name, const std::string& fallback) {
    if (!j.contains(name)) return fallback;
    if (!j.at(name).is_string())
      throw InputError(path + ": field '" + name +
                       "' must be a text in quotes; see data/piles/default.json");
    return j.at(name).get<std::string>();
  };
  p.name = text("name", path);
  p.source = text("source", "");
  if (!field("width_m").is_number() || !(field("width_m").get<double>() > 0.0) ||
      field("width_m").get<double>() > kMaxProfileExtent)
    throw InputError(path + ": field 'width_m' must be a positive number of at most 100 [m]");
  p.width = field("width_m").get<double>();
  const auto& pts = field("profile_xz_m");
  if (!pts.is_array() || pts.size() < 2)
    throw InputError(path + ": field 'profile_xz_m' must list at least two [x, z] points");
  for (size_t k = 0; k < pts.size(); ++k) {
    const auto& q = pts[k];
    if (!q.is_array() || q.size() != 2 || !q[0].is_number() || !q[1].is_number())
      throw InputError(path + ": field 'profile_xz_m[" + std::to_string(k) +
                       "]' must be a pair [x, z] of numbers in metres");
    double x = q[0].get<double>(), z = q[1].get<double>();
    if (!std::isfinite(x) || !std::isfinite(z) || z < 0.0)
      throw InputError(path + ": field 'profile_xz_m[" + std::to_string(k) +
                       "]' must be finite with z >= 0");
    if (std::abs(x) > kMaxProfileExtent || z > kMaxProfileExtent)
      throw InputError(path + ": field 'profile_xz_m[" + std::to_string(k) +
                       "]' lies more than 100 m from the origin; give the surface in metres (the "
                       "field's pile: 2 m high)");
    if (!p.points.empty() && x <= p.points.back().x())
      throw InputError(path + ": field 'profile_xz_m' must have increasing x (point " +
                       std::to_string(k) + ")");
    p.points.emplace_back(x, 0.0, z);
  }
  if (!field("rear_wall_x_m").is_number())
    throw InputError(path + ": field 'rear_wall_x_m' must be a number [m]");
  p.rear_wall_x = field("rear_wall_x_m").get<double>();
  if (p.rear_wall_x < p.points.back().x() - 1e-9)
    throw InputError(path + ": field 'rear_wall_x_m' must not lie in front of the last profile point");
  if (!std::isfinite(p.rear_wall_x) || std::abs(p.rear_wall_x) > kMaxProfileExtent)
    throw InputError(
        path + ": field 'rear_wall_x_m' lies more than 100 m from the origin; give it in metres");
  if (!(p.cross_section() > 0.0))
    throw InputError(path +
                     ": field 'profile_xz_m' encloses no soil (every height is 0); give the "
                     "surface's heights in metres");
  return p;
}

PileProfile default_pile_profile() { return load_pile_profile(find_data_file("piles/default.json")); }

const std::vector<FidelityPreset>& fidelity_presets() {
  // paper Table 3 (type D): D, timestep, particle count, PGS iterations
  static const std::vector<FidelityPreset> presets = {
      {"D50", 0.050, 0.002, 200, 450000},
      {"D100", 0.100, 0.005, 100, 55000},
      {"D200", 0.200, 0.010, 500, 6100},
      {"D400", 0.400, 0.020, 15, 800},
  };
  return presets;
}

const std::vector<FidelityPreset>& multiscale_presets() {
  // paper Table 3 (type G): voxel cell and particle size, timestep, PGS iterations, most particles
  static const std::vector<FidelityPreset> presets = {
      {"G50", 0.050, 0.005, 50, 28000},
      {"G100", 0.100, 0.010, 25, 3500},
      {"G200", 0.200, 0.020, 15, 480},
      {"G400", 0.400, 0.050, 10, 55},
  };
  return presets;
}

const FidelityPreset* find_multiscale_preset(const std::string& name) {
  for (auto& p : multiscale_presets())
    if (p.name == name) return &p;
  return nullptr;
}

bool is_multiscale(const FidelityPreset& preset) {
  return find_multiscale_preset(preset.name) != nullptr;
}

DeviceChoice device_choice_for(const FidelityPreset& preset) {
  DeviceChoice choice = device_choice_from_env();
  choice.in_host_thread = is_multiscale(preset) && preset.paper_particles <= kInHostThreadParticles;
  return choice;
}

DeviceChoice device_choice_for(const std::vector<const FidelityPreset*>& presets) {
  DeviceChoice choice = device_choice_from_env();
  choice.in_host_thread = !presets.empty();
  for (const FidelityPreset* p : presets)
    choice.in_host_thread = choice.in_host_thread && device_choice_for(*p).in_host_thread;
  return choice;
}

const FidelityPreset& fidelity_preset(const std::string& name) {
  std::string known;
  for (auto& p : fidelity_presets()) {
    if (p.name == name) return p;
    known += " " + p.name;
  }
  // the type-G levels are named, so a user asking for one learns what they are for
  if (find_multiscale_preset(name))
    throw InputError(
        "fidelity level '" + name +
        "' is the multiscale (type G) terrain: it runs scenarios (talus run, sweep, synth, "
        "diagnose), the cutting test (talus cut) and the dig's cost (talus bench dig), but has no "
        "particle pile, shear, collapse or heap test, or DEM benchmark of its own "
        "(docs/multiscale.md). Here use a type-D level:" +
        known);
  throw InputError("unknown fidelity level '" + name + "'; known:" + known);
}

const FidelityPreset& level_preset(const std::string& name) {
  if (const FidelityPreset* g = find_multiscale_preset(name)) return *g;
  std::string known;
  for (auto& p : fidelity_presets()) {
    if (p.name == name) return p;
    known += " " + p.name;
  }
  for (auto& p : multiscale_presets()) known += " " + p.name;
  throw InputError("unknown fidelity level '" + name + "'; known:" + known);
}

std::vector<StaticGeom> pile_container(const PileProfile& profile) {
  double half_width = 0.5 * profile.width;
  return {
      StaticGeom::plane(Vec3(0, 0, 0), Vec3(0, 0, 1)),                   // ground
      StaticGeom::plane(Vec3(0, -half_width, 0), Vec3(0, 1, 0)),         // right side wall
      StaticGeom::plane(Vec3(0, half_width, 0), Vec3(0, -1, 0)),         // left side wall
      StaticGeom::plane(Vec3(profile.rear_wall_x, 0, 0), Vec3(-1, 0, 0)) // rear wall
  };
}

// rising segments of the profile: (start, end) in the x-z plane
std::vector<std::pair<Vec3, Vec3>> rising_segments(const PileProfile& profile) {
  std::vector<std::pair<Vec3, Vec3>> out;
  for (size_t k = 1; k < profile.points.size(); ++k)
    if (profile.points[k].z() > profile.points[k - 1].z()) out.emplace_back(profile.points[k - 1], profile.points[k]);
  return out;
}

bool behind_faces(const PileProfile& profile, double x, double z) {
  if (x < profile.points.front().x() || x > profile.rear_wall_x || z < 0.0) return false;
  for (auto& [p0, p1] : rising_segments(profile)) {
    // above the face's top the formwork is vertical
    if (z > p1.z()) {
      if (x < p1.x()) return false;
      continue;
    }
    // outward normal of a rising face points up and forward: (-dz, dx) in (x, z)
    Vec3 t = p1 - p0;
    double out_x = -t.z(), out_z = t.x();
    if ((x - p0.x()) * out_x + (z - p0.z()) * out_z > 0.0) return false;
  }
  return true;
}

std::vector<StaticGeom> pile_forms(const PileProfile& profile) {
  // per rising face: a 2 m thick box in front of it (extended 1 m below the toe), and a
  // vertical plate above its top holding the taller loose lattice (behind_faces agrees)
  const double thickness = 2.0, below = 1.0, plate_height = 6.0;
  double half_y = 0.5 * profile.width + 1.0;
  std::vector<StaticGeom> forms;
  for (auto& [p0, p1] : rising_segments(profile)) {
    Vec3 t = (p1 - p0).normalized();
    Vec3 out(-t.z(), 0.0, t.x());
    double length = (p1 - p0).norm() + below;
    Vec3 mid = p0 - below * t + 0.5 * length * t + 0.5 * thickness * out;
    Eigen::Matrix3d axes;
    axes.col(0) = t;
    axes.col(1) = Vec3::UnitY();
    axes.col(2) = out;
    forms.push_back(StaticGeom::box(mid, Vec3(0.5 * length, half_y, 0.5 * thickness), axes));
    Vec3 plate(p1.x() - 0.5 * thickness, 0.0, p1.z() + 0.5 * plate_height);
    forms.push_back(StaticGeom::box(plate, Vec3(0.5 * thickness, half_y, 0.5 * plate_height),
                                    Eigen::Matrix3d::Identity()));
  }
  return forms;
}

Bounds pile_bounds(const PileProfile& profile, double diameter) {
  // room in front of the toe for the face to slump and above the top for the loose lattice
  double top = 0.0;
  for (auto& p : profile.points) top = std::max(top, p.z());
  Bounds b;
  b.lo = Vec3(profile.points.front().x() - 2.0 * top - 4 * diameter, -0.5 * profile.width, 0.0);
  b.hi = Vec3(profile.rear_wall_x, 0.5 * profile.width, 3.5 * top + 4 * diameter);
  return b;
}

double estimated_pile_particles(const PileProfile& profile, double diameter) {
  return kEmissionSolidFraction * profile.volume() / (M_PI / 6.0 * diameter * diameter * diameter);
}

Particles emit_pile_particles(const PileProfile& profile, double diameter, const Material& material,
                              unsigned seed, double settled_fraction) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> size(0.9 * diameter, 1.1 * diameter);
  // lattice spacing: the largest diameter plus a gap, so no two spheres start overlapping
  double spacing = 1.1 * diameter * 1.02;
  double jitter = 0.5 * (spacing - 1.1 * diameter);
  std::uniform_real_distribution<double> offset(-jitter, jitter);
  double target = settled_fraction * profile.volume();
  double half_width = 0.5 * profile.width;
  Particles particles;
  int ny = static_cast<int>(std::floor((profile.width - spacing) / spacing)) + 1;
  double y0 = -half_width + 0.5 * spacing + 0.5 * (profile.width - spacing - (ny - 1) * spacing);
  // layers from the ground up; in each, columns from the rear wall forward, rows along y
  double solid = 0.0;
  double z_max = 10.0 * profile.height_at(profile.rear_wall_x) + 10.0 * spacing;
  for (double z = 0.5 * spacing; solid < target && z < z_max; z += spacing) {
    for (double x = profile.rear_wall_x - 0.5 * spacing; x > profile.points.front().x() && solid < target;
         x -= spacing) {
      if (!behind_faces(profile, x, z)) continue;
      for (int iy = 0; iy < ny && solid < target; ++iy) {
        Vec3 jit(offset(rng), offset(rng), offset(rng));
        double r = 0.5 * size(rng);
        particles.add(Vec3(x, y0 + iy * spacing, z) + jit, r, material.density);
        solid += 4.0 / 3.0 * M_PI * r * r * r;
      }
    }
  }
  // filled layer by layer, stored column by column: neighbours stay near in memory
  return particles.permuted(spatial_order(particles, spacing));
}

double bulk_density(const Particles& particles, const Bounds& box, double particle_density) {
  double solid = 0.0;
  for (size_t i = 0; i < particles.size(); ++i) {
    const Vec3& x = particles.position[i];
    if ((x.array() >= box.lo.array()).all() && (x.array() <= box.hi.array()).all()) {
      double r = particles.radius[i];
      solid += 4.0 / 3.0 * M_PI * r * r * r;
    }
  }
  Vec3 e = box.hi - box.lo;
  return particle_density * solid / (e.x() * e.y() * e.z());
}

}  // namespace talus

#include "terrain/heightmap.hpp"
#include "terrain/settle.hpp"
#include "terrain/soil_sample.hpp"

namespace talus {

PileScan scan_pile(const Particles& particles, const PileProfile& profile, double diameter) {
  // heightmap over the container and the run-out in front of it
  double top = 0.0;
  for (auto& p : profile.points) top = std::max(top, p.z());
  double x0 = profile.points.front().x() - 2.0 * top;
  int nx = static_cast<int>(std::ceil((profile.rear_wall_x - x0) / diameter)) + 1;
  int ny = static_cast<int>(std::ceil(profile.width / diameter)) + 1;
  // the ground (z = 0) under every node, so bins without particles read as ground, not as holes
  // filled from their neighbours (the heightmap reads positions and radii only)
  Particles surface = particles;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      surface.position.emplace_back(x0 + i * diameter, -0.5 * profile.width + j * diameter, 0.0);
      surface.radius.push_back(0.0);
    }
  Heightmap map = Heightmap::from_particles(surface, x0, -0.5 * profile.width, diameter, nx, ny);
  return scan_surface(map, profile);
}

PileScan scan_surface(const Heightmap& map, const PileProfile& profile) {
  double top = 0.0;
  for (auto& p : profile.points) top = std::max(top, p.z());
  const double x0 = profile.points.front().x() - 2.0 * top;
  // the laser: 800 rays in the mid plane from in front of the toe, aimed at ground points from the
  // run-out to far behind the rear wall: the rays aimed behind the pile are the ones that graze
  // its top (those that pass over the wall leave the map and are dropped)
  const double sensor_back = 3.0, sensor_up = 3.0;  // [m] a scanner on a tripod in front
  const double beyond = 10.0 * sensor_up;           // [m] aim past the wall: rays down to ~1/10 slope
  Eigen::Vector3d sensor(profile.points.front().x() - sensor_back, 0.0, sensor_up);
  PileScan scan;
  scan.points = map.scan_profile(0.0, x0, profile.rear_wall_x + beyond, 800, sensor);
  // the face: a line through the points between 20% and 80% of the highest
  double zmax = 0.0;
  for (auto& q : scan.points) zmax = std::max(zmax, q.y());
  double n = 0, sx = 0, sz = 0, sxx = 0, sxz = 0;
  for (auto& q : scan.points) {
    if (q.y() < 0.2 * zmax || q.y() > 0.8 * zmax) continue;
    n += 1;
    sx += q.x();
    sz += q.y();
    sxx += q.x() * q.x();
    sxz += q.x() * q.y();
  }
  if (n >= 3) scan.face_angle_deg = std::atan((n * sxz - sx * sz) / (n * sxx - sx * sx)) * 180.0 / M_PI;
  // the scan against the profile it was built to, where the profile stands
  double count = 0, sum = 0, sum_sq = 0;
  for (auto& q : scan.points) {
    if (q.x() < profile.points.front().x() || q.x() > profile.rear_wall_x) continue;
    const double e = q.y() - profile.height_at(q.x());
    count += 1;
    sum += e;
    sum_sq += e * e;
  }
  if (count > 0) {
    scan.mean_to_profile_m = sum / count;
    scan.rms_to_profile_m = std::sqrt(sum_sq / count);
  }
  return scan;
}

ProfileFit bulk_fit_to_profile(const Particles& particles, const PileProfile& profile,
                               double diameter) {
  // strips of 2 D along x over the middle half of the width
  const double strip = 2.0 * diameter;
  const double x0 = profile.points.front().x();
  const int n = std::max(1, static_cast<int>(std::floor((profile.rear_wall_x - x0) / strip)));
  const double half_width = 0.25 * profile.width;
  std::vector<double> mass(static_cast<size_t>(n), 0.0);
  for (size_t i = 0; i < particles.size(); ++i) {
    if (particles.inv_mass[i] <= 0.0) continue;
    const Vec3& x = particles.position[i];
    const int k = static_cast<int>(std::floor((x.x() - x0) / strip));
    if (k < 0 || k >= n || std::abs(x.y()) > half_width) continue;
    mass[static_cast<size_t>(k)] += 1.0 / particles.inv_mass[i];
  }
  // each strip's soil height against the profile's mean height over the strip
  constexpr int kProfileSamples = 8;  // midpoints per strip: the profile is piecewise linear
  double sum = 0.0, sum_sq = 0.0;
  for (int k = 0; k < n; ++k) {
    const double soil =
        mass[static_cast<size_t>(k)] / (strip * 2.0 * half_width * kFieldBulkDensity);
    double built = 0.0;
    for (int j = 0; j < kProfileSamples; ++j)
      built += profile.height_at(x0 + (k + (j + 0.5) / kProfileSamples) * strip) / kProfileSamples;
    sum += soil - built;
    sum_sq += (soil - built) * (soil - built);
  }
  return {std::sqrt(sum_sq / n), sum / n};
}

double profile_toe(const PileProfile& profile) {
  for (size_t k = 1; k < profile.points.size(); ++k) {
    const Vec3& p0 = profile.points[k - 1];
    const Vec3& p1 = profile.points[k];
    if (p1.z() >= kToeHeight && p0.z() < kToeHeight)
      return p0.x() + (p1.x() - p0.x()) * (kToeHeight - p0.z()) / (p1.z() - p0.z());
  }
  return profile.points.empty() ? 0.0 : profile.points.front().x();
}

double particle_toe(const Particles& particles, const PileProfile& profile, double d) {
  // bins of D from well in front of the profile's toe towards the rear wall
  const double quarter = 0.25 * profile.width;
  const double start = pile_bounds(profile, d).lo.x();
  double previous = 0.0;
  for (double x = start; x < profile.rear_wall_x; x += d) {
    const double h = mean_surface(particles, x, x + d, -quarter, quarter, d);
    if (h >= kToeHeight) {
      // linear between the bins' centres
      const double s = (kToeHeight - previous) / std::max(h - previous, 1e-12);
      return x - 0.5 * d + s * d;
    }
    previous = h;
  }
  return profile.rear_wall_x;
}

int settle_sweeps(const FidelityPreset& preset, const PileBuildOptions& options) {
  return options.settle_iterations > 0 ? options.settle_iterations
                                       : std::min(preset.iterations, kSettleIterationCap);
}

void check_device_memory(double particles, std::size_t global_bytes,
                         std::size_t max_allocation_bytes, const std::string& where,
                         const std::string& level) {
  const double mib = 1024.0 * 1024.0;
  const double all = particles * kDemDeviceBytesPerParticle;
  const double largest = particles * kDemLargestBufferBytesPerParticle;
  const auto text = [&](double bytes) { return message_number(std::round(bytes / mib)) + " MiB"; };
  const std::string pile = where + ": the pile needs about " +
                           message_number(std::round(particles)) + " particles at " + level;
  const std::string fix =
      "; use a coarser level, a smaller pile or a device with more memory (TALUS_DEVICE)";
  if (!(all <= static_cast<double>(global_bytes)))
    throw InputError(pile + ", about " + text(all) + " of device memory (" +
                     message_number(kDemDeviceBytesPerParticle) +
                     " bytes a particle), more than the device's " +
                     text(static_cast<double>(global_bytes)) + fix);
  if (!(largest <= static_cast<double>(max_allocation_bytes)))
    throw InputError(pile + ", whose contacts need one buffer of about " + text(largest) +
                     ", more than the device allocates at once (" +
                     text(static_cast<double>(max_allocation_bytes)) + ")" + fix);
}

PileBuild build_pile(Device& dev, const PileProfile& profile, const FidelityPreset& preset,
                     const Material& material, const PileBuildOptions& options, Progress* progress) {
  // a formwork speed that cannot be used, before anything is built
  if (options.form_speed > 0.0 && options.form_speed < 0.01)
    throw InputError("--form-speed " + std::to_string(options.form_speed) +
                     " m/s: give 0 (formwork removed at once) or at least 0.01 m/s");
  if (options.form_speed > 0.0 && options.hold_face)
    throw InputError("--form-speed " + std::to_string(options.form_speed) +
                     " m/s withdraws the formwork before the pile settles, which a held face keeps "
                     "until the dig: add --free-face to settle the pile free");
  // a pile sized by mistake is refused before it is filled (kMaxPileParticles)
  const double needed = estimated_pile_particles(profile, preset.diameter);
  if (needed > kMaxPileParticles) {
    const std::string where =
        profile.path.empty() ? "pile profile '" + profile.name + "'" : profile.path;
    throw InputError(where + ": the pile (" +
                     std::to_string(static_cast<long long>(profile.volume())) +
                     " m^3) needs about " + std::to_string(static_cast<long long>(needed)) +
                     " particles at " + preset.name +
                     ", more than talus builds (4,500,000, ten times D50's); check that "
                     "'profile_xz_m' and 'width_m' are in metres, or use a coarser level");
  }
  // and one that the device cannot hold, before the first buffer is made
  check_device_memory(needed, dev.global_memory(), dev.max_allocation(),
                      profile.path.empty() ? "pile profile '" + profile.name + "'" : profile.path,
                      preset.name);
  PileBuild out;
  out.geoms = pile_container(profile);
  out.bounds = pile_bounds(profile, preset.diameter);
  DemSettings settings;
  settings.dt = preset.dt;
  settings.iterations = settle_sweeps(preset, options);
  // dense fill: friction off, the faces held by formwork (as gravel dumped and compacted)
  Material fill = material;
  fill.friction = 0.0;
  fill.rolling = 0.0;
  std::vector<StaticGeom> formed = out.geoms;
  for (auto& f : pile_forms(profile)) formed.push_back(f);
  DemWorld world(dev, fill, settings, out.bounds, formed);
  world.set_particles(emit_pile_particles(profile, preset.diameter, material, options.seed));
  SettleOptions so;
  so.min_time = 0.5 * options.min_time;
  so.max_time = 0.5 * options.max_time;
  so.rest_speed = 0.02;
  const SettleResult filled = settle(world, so, progress);
  out.fill_time = filled.sim_time;
  out.fill_at_rest = filled.at_rest;
  out.fill_rms_speed = filled.rms_speed;
  out.settle_iterations = settings.iterations;
  // the gravel's friction on; the formwork withdraws (along -x, away from the faces), then goes,
  // and the pile settles into its own shape; or it stays and the pile settles against it
  // (hold_face: the face goes when the pile is used, out.geoms never held it)
  world.set_material(material);
  if (options.form_speed > 0.0) {
    const int steps = static_cast<int>(std::lround(options.form_travel / (options.form_speed * settings.dt)));
    for (int k = 1; k <= steps; ++k) {
      std::vector<StaticGeom> moved = out.geoms;
      for (StaticGeom f : pile_forms(profile)) {
        f.centre.x() -= k * options.form_speed * settings.dt;
        moved.push_back(f);
      }
      world.set_geoms(moved, GeomChange::Moved);
      world.step();
      if (progress) progress->update(world.time(), "formwork withdrawing");
    }
  }
  if (!options.hold_face) world.set_geoms(out.geoms);
  so.min_time = options.min_time;
  so.max_time = options.max_time;
  SettleResult r = settle(world, so, progress);
  out.particles = world.particles();
  out.device_bytes = world.buffers().device_bytes();
  out.largest_buffer_bytes = world.buffers().largest_buffer_bytes();
  out.settle_time = r.sim_time;
  out.at_rest = r.at_rest;
  out.rms_speed = r.rms_speed;
  // bulk density in the core of the flat top: two diameters from walls, ground and surface
  double d = preset.diameter;
  double top = 0.0;
  for (auto& p : profile.points) top = std::max(top, p.z());
  // the flat top starts where the profile first reaches its full height
  double flat_start = profile.points.back().x();
  for (auto& p : profile.points)
    if (p.z() >= top) {
      flat_start = p.x();
      break;
    }
  Bounds core{Vec3(flat_start + 2 * d, -0.5 * profile.width + 2 * d, 2 * d),
              Vec3(profile.rear_wall_x - 2 * d, 0.5 * profile.width - 2 * d, 0.75 * top)};
  out.bulk_density = bulk_density(out.particles, core, material.density);
  if (options.place_toe) {
    // the pile moves as one, container and all, so its toe lies where the profile's does
    const double dx = profile_toe(profile) - particle_toe(out.particles, profile, preset.diameter);
    for (Vec3& x : out.particles.position) x.x() += dx;
    for (StaticGeom& g : out.geoms) g.centre.x() += dx;
    out.bounds.lo.x() += dx;
    out.bounds.hi.x() += dx;
    out.toe_shift = dx;
  }
  out.soil_fit = bulk_fit_to_profile(out.particles, profile, preset.diameter);
  return out;
}

}  // namespace talus
