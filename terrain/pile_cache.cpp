#include "terrain/pile_cache.hpp"

#include <array>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string_view>

#include "host/binary.hpp"
#include "host/error.hpp"
#include "host/files.hpp"
#include "host/version.hpp"

namespace talus {

namespace {

// the file's magic, version and what a user does about a bad one (the cache treats it as a miss)
const SealedFormat& pile_format() {
  static const SealedFormat format{"TALUSPIL", kPileFormatVersion, "pile",
                                   "delete it, the pile is built again"};
  return format;
}
// bytes per particle in the file: 3 vectors of 3, a quaternion, radius, inverse mass and inertia
constexpr std::uint64_t kParticleBytes = 8 * (3 * 3 + 4 + 3);
// bytes per geom: its type, then centre (3), axes (9) and half extents (3)
constexpr std::uint64_t kGeomBytes = 1 + 8 * (3 + 9 + 3);

void write_vec(ByteWriter& w, const Vec3& v) { w.f64s(v.data(), 3); }
Vec3 read_vec(ByteReader& r, const char* what) {
  Vec3 v;
  r.f64s(v.data(), 3, what);
  return v;
}

// a profile that says where it came from in a note
std::string describe(const PileProfile& profile, const FidelityPreset& preset) {
  return (profile.name.empty() ? std::string("pile") : profile.name) + " at " + preset.name;
}

}  // namespace

std::string pile_key_name(const std::string& key_bytes) { return key_file_name(key_bytes); }

std::string pile_key_bytes(const PileProfile& profile, const FidelityPreset& preset,
                           const Material& material, const PileBuildOptions& options,
                           const std::string& device, const std::string& commit) {
  // each part named, so two keys that differ only in where a field ends cannot coincide
  ByteWriter w;
  w.str("profile");
  w.f64(profile.width);
  w.f64(profile.rear_wall_x);
  w.u64(profile.points.size());
  for (const Vec3& p : profile.points) write_vec(w, p);
  w.str("preset");
  w.str(preset.name);
  w.f64(preset.diameter);
  w.f64(preset.dt);
  w.u64(static_cast<std::uint64_t>(static_cast<std::int64_t>(preset.iterations)));
  w.str("material");
  for (double v :
       {material.density, material.young, material.poisson, material.friction, material.rolling,
        material.ground_rolling, material.damping_steps, material.cohesion})
    w.f64(v);
  w.str("options");
  w.u64(options.seed);
  // the sweeps the pile is settled with, as the rule or the study resolved them
  w.u64(static_cast<std::uint64_t>(static_cast<std::int64_t>(settle_sweeps(preset, options))));
  for (double v : {options.min_time, options.max_time, options.form_speed, options.form_travel})
    w.f64(v);
  w.u8(options.place_toe ? 1 : 0);
  w.u8(options.hold_face ? 1 : 0);
  w.str("device");
  w.str(device);
  w.str("commit");
  w.str(commit);
  return std::move(w.bytes());
}

std::string serialise_pile(const PileBuild& pile, const std::string& key) {
  ByteWriter w;
  begin_sealed(w, pile_format());
  w.str(key);
  // the recorded numbers of the build
  w.f64(pile.fill_time);
  w.u8(pile.fill_at_rest ? 1 : 0);
  w.f64(pile.fill_rms_speed);
  w.f64(pile.settle_time);
  w.u8(pile.at_rest ? 1 : 0);
  w.f64(pile.rms_speed);
  w.u64(static_cast<std::uint64_t>(static_cast<std::int64_t>(pile.settle_iterations)));
  w.f64(pile.bulk_density);
  w.f64(pile.toe_shift);
  w.f64(pile.soil_fit.rms_m);
  w.f64(pile.soil_fit.mean_m);
  write_vec(w, pile.bounds.lo);
  write_vec(w, pile.bounds.hi);
  // the container
  w.u64(pile.geoms.size());
  for (const StaticGeom& g : pile.geoms) {
    w.u8(g.type == StaticGeom::Type::Box ? 1 : 0);
    write_vec(w, g.centre);
    for (int c = 0; c < 3; ++c) write_vec(w, g.axes.col(c));
    write_vec(w, g.half);
  }
  // the particles, array by array as Particles stores them
  const Particles& p = pile.particles;
  const std::size_t n = p.size();
  if (p.velocity.size() != n || p.omega.size() != n || p.rotation.size() != n ||
      p.radius.size() != n || p.inv_mass.size() != n || p.inv_inertia.size() != n)
    throw Error("serialise_pile: the particles' arrays differ in length");
  w.u64(n);
  for (const Vec3& v : p.position) write_vec(w, v);
  for (const Vec3& v : p.velocity) write_vec(w, v);
  for (const Vec3& v : p.omega) write_vec(w, v);
  for (const Eigen::Vector4d& q : p.rotation)
    for (int k = 0; k < 4; ++k) w.f64(q[k]);
  for (double v : p.radius) w.f64(v);
  for (double v : p.inv_mass) w.f64(v);
  for (double v : p.inv_inertia) w.f64(v);
  // the checksum of everything before it
  end_sealed(w);
  return std::move(w.bytes());
}

PileBuild parse_pile(const std::string& bytes, const std::string& where, std::string* key) {
  // magic, version and checksum checked before anything is read
  ByteReader r = open_sealed(bytes, pile_format(), where);
  std::string stored_key = r.str("key");
  PileBuild pile;
  pile.fill_time = r.f64("numbers");
  pile.fill_at_rest = r.u8("numbers") != 0;
  pile.fill_rms_speed = r.f64("numbers");
  pile.settle_time = r.f64("numbers");
  pile.at_rest = r.u8("numbers") != 0;
  pile.rms_speed = r.f64("numbers");
  pile.settle_iterations = static_cast<int>(static_cast<std::int64_t>(r.u64("numbers")));
  pile.bulk_density = r.f64("numbers");
  pile.toe_shift = r.f64("numbers");
  pile.soil_fit.rms_m = r.f64("numbers");
  pile.soil_fit.mean_m = r.f64("numbers");
  pile.bounds.lo = read_vec(r, "bounds");
  pile.bounds.hi = read_vec(r, "bounds");
  // counts are checked against the bytes left before anything is allocated
  const std::uint64_t geoms = r.u64("geoms");
  r.need_elements(geoms, kGeomBytes, "geoms");
  pile.geoms.resize(geoms);
  for (StaticGeom& g : pile.geoms) {
    g.type = r.u8("geoms") != 0 ? StaticGeom::Type::Box : StaticGeom::Type::Plane;
    g.centre = read_vec(r, "geoms");
    for (int c = 0; c < 3; ++c) g.axes.col(c) = read_vec(r, "geoms");
    g.half = read_vec(r, "geoms");
  }
  const std::uint64_t n = r.u64("particles");
  r.need_elements(n, kParticleBytes, "particles");
  Particles& p = pile.particles;
  p.position.resize(n);
  p.velocity.resize(n);
  p.omega.resize(n);
  p.rotation.resize(n);
  p.radius.resize(n);
  p.inv_mass.resize(n);
  p.inv_inertia.resize(n);
  for (Vec3& v : p.position) v = read_vec(r, "particles");
  for (Vec3& v : p.velocity) v = read_vec(r, "particles");
  for (Vec3& v : p.omega) v = read_vec(r, "particles");
  for (Eigen::Vector4d& q : p.rotation)
    for (int k = 0; k < 4; ++k) q[k] = r.f64("particles");
  for (double& v : p.radius) v = r.f64("particles");
  for (double& v : p.inv_mass) v = r.f64("particles");
  for (double& v : p.inv_inertia) v = r.f64("particles");
  if (r.left() != 0)
    throw InputError(where + ": " + std::to_string(r.left()) +
                     " bytes after the particles (corrupt); delete it, the pile is built again");
  if (key) *key = std::move(stored_key);
  return pile;
}

void write_pile(const std::string& path, const PileBuild& pile, const std::string& key) {
  write_file_atomically(path, serialise_pile(pile, key));
}

PileBuild read_pile(const std::string& path, std::string* key) {
  return parse_pile(read_file_bytes(path, "a settled pile"), path, key);
}

PileBuild build_pile_cached(Device& dev, const PileProfile& profile, const FidelityPreset& preset,
                            const Material& material, const PileBuildOptions& options,
                            const PileCacheOptions& cache, Progress* progress) {
  const auto note = [&](const std::string& line) {
    if (cache.note) cache.note(line);
  };
  if (!cache.enabled) return build_pile(dev, profile, preset, material, options, progress);
  // a build with uncommitted changes has no commit that names its code: a pile it saved could be
  // read by a later build of other code
  const std::string commit = cache.commit.empty() ? std::string(git_commit()) : cache.commit;
  const std::string dirty = "-dirty";
  if (commit.size() >= dirty.size() &&
      commit.compare(commit.size() - dirty.size(), dirty.size(), dirty) == 0) {
    note("pile cache not used: this build (" + commit +
         ") has uncommitted changes, so a saved pile could be stale; commit them to use it");
    return build_pile(dev, profile, preset, material, options, progress);
  }
  const std::string root = cache.dir.empty() ? default_cache_dir() : cache.dir;
  if (root.empty()) {
    note("pile cache not used: neither TALUS_CACHE_DIR, XDG_CACHE_HOME nor HOME is set");
    return build_pile(dev, profile, preset, material, options, progress);
  }
  const std::filesystem::path folder = std::filesystem::path(root) / "piles";
  const std::string key =
      pile_key_bytes(profile, preset, material, options, dev.description(), commit);
  const std::string file = (folder / (pile_key_name(key) + ".pile")).string();

  // a hit: the file is there, whole, of this version and under this very key
  std::error_code ec;
  if (std::filesystem::exists(file, ec)) {
    try {
      std::string stored;
      PileBuild pile = read_pile(file, &stored);
      if (stored == key) {
        pile.from_cache = true;
        pile.cache_file = file;
        note("pile from cache " + file);
        return pile;
      }
      note("pile cache: " + file + " holds another pile under the same hash; building " +
           describe(profile, preset) + " and replacing it");
    } catch (const Error& e) {
      note(std::string("pile cache: ") + e.what());
    }
  }

  // a miss: build, then save for the next run (a folder that refuses the file only loses that)
  PileBuild pile = build_pile(dev, profile, preset, material, options, progress);
  std::filesystem::create_directories(folder, ec);
  if (ec) {
    note("pile cache: cannot create " + folder.string() + " (" + ec.message() +
         "); the pile is not saved (set TALUS_CACHE_DIR to a writable folder)");
    return pile;
  }
  try {
    write_pile(file, pile, key);
    pile.cache_file = file;
    note("pile saved to cache " + file);
  } catch (const Error& e) {
    note(std::string("pile cache: ") + e.what() +
         "; the pile is not saved (set TALUS_CACHE_DIR to a writable folder)");
  }
  return pile;
}

}  // namespace talus
