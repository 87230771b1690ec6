#include "terrain/pile_cache.hpp"

#include <array>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string_view>

#include "host/error.hpp"
#include "host/files.hpp"
#include "host/version.hpp"

namespace talus {

namespace {

// the file's first bytes: what it is, before its version
constexpr std::array<char, 8> kMagic = {'T', 'A', 'L', 'U', 'S', 'P', 'I', 'L'};
// FNV-1a's 64-bit parameters (Fowler, Noll, Vo; http://www.isthe.com/chongo/tech/comp/fnv/)
constexpr std::uint64_t kFnvOffset = 14695981039346656037ULL;
constexpr std::uint64_t kFnvPrime = 1099511628211ULL;
// bytes per particle in the file: 3 vectors of 3, a quaternion, radius, inverse mass and inertia
constexpr std::uint64_t kParticleBytes = 8 * (3 * 3 + 4 + 3);
// bytes per geom: its type, then centre (3), axes (9) and half extents (3)
constexpr std::uint64_t kGeomBytes = 1 + 8 * (3 + 9 + 3);

// little-endian bytes, whatever the machine's order, so a file moves between machines
class Writer {
 public:
  void u8(std::uint8_t v) { out_.push_back(static_cast<char>(v)); }
  void u32(std::uint32_t v) {
    for (int b = 0; b < 4; ++b) u8(static_cast<std::uint8_t>(v >> (8 * b)));
  }
  void u64(std::uint64_t v) {
    for (int b = 0; b < 8; ++b) u8(static_cast<std::uint8_t>(v >> (8 * b)));
  }
  // a double bit for bit (NaN payloads and signed zeros included)
  void f64(double v) {
    std::uint64_t bits = 0;
    std::memcpy(&bits, &v, sizeof bits);
    u64(bits);
  }
  void str(const std::string& s) {
    u64(s.size());
    out_ += s;
  }
  void vec(const Vec3& v) {
    for (int k = 0; k < 3; ++k) f64(v[k]);
  }
  std::string& bytes() { return out_; }

 private:
  std::string out_;
};

// the same bytes read back; every read checks the length first, so a short file is named, not
// read past its end
class Reader {
 public:
  Reader(std::string_view bytes, std::size_t end, std::string where)
      : bytes_(bytes), end_(end), where_(std::move(where)) {}
  void need(std::uint64_t n, const char* what) const {
    if (n > end_ - pos_)
      throw InputError(where_ + ": the file ends inside its " + what +
                       " (truncated or not a talus pile); delete it, the pile is built again");
  }
  std::uint8_t u8(const char* what) {
    need(1, what);
    return static_cast<std::uint8_t>(bytes_[pos_++]);
  }
  std::uint32_t u32(const char* what) {
    need(4, what);
    std::uint32_t v = 0;
    for (int b = 0; b < 4; ++b)
      v |= static_cast<std::uint32_t>(static_cast<std::uint8_t>(bytes_[pos_++])) << (8 * b);
    return v;
  }
  std::uint64_t u64(const char* what) {
    need(8, what);
    std::uint64_t v = 0;
    for (int b = 0; b < 8; ++b)
      v |= static_cast<std::uint64_t>(static_cast<std::uint8_t>(bytes_[pos_++])) << (8 * b);
    return v;
  }
  double f64(const char* what) {
    const std::uint64_t bits = u64(what);
    double v = 0.0;
    std::memcpy(&v, &bits, sizeof v);
    return v;
  }
  std::string str(const char* what) {
    const std::uint64_t n = u64(what);
    need(n, what);
    std::string s(bytes_.substr(pos_, n));
    pos_ += n;
    return s;
  }
  Vec3 vec(const char* what) {
    Vec3 v;
    for (int k = 0; k < 3; ++k) v[k] = f64(what);
    return v;
  }
  std::size_t left() const { return end_ - pos_; }

 private:
  std::string_view bytes_;
  std::size_t end_;
  std::size_t pos_ = 0;
  std::string where_;
};

std::string hex16(std::uint64_t v) {
  std::ostringstream s;
  s.width(16);
  s.fill('0');
  s << std::hex << v;
  return s.str();
}

// a profile that says where it came from in a note
std::string describe(const PileProfile& profile, const FidelityPreset& preset) {
  return (profile.name.empty() ? std::string("pile") : profile.name) + " at " + preset.name;
}

}  // namespace

std::uint64_t fnv1a64(const std::string& bytes) {
  std::uint64_t h = kFnvOffset;
  for (char c : bytes) {
    h ^= static_cast<std::uint8_t>(c);
    h *= kFnvPrime;
  }
  return h;
}

std::string pile_key_name(const std::string& key_bytes) { return hex16(fnv1a64(key_bytes)); }

std::string pile_key_bytes(const PileProfile& profile, const FidelityPreset& preset,
                           const Material& material, const PileBuildOptions& options,
                           const std::string& device, const std::string& commit) {
  // each part named, so two keys that differ only in where a field ends cannot coincide
  Writer w;
  w.str("profile");
  w.f64(profile.width);
  w.f64(profile.rear_wall_x);
  w.u64(profile.points.size());
  for (const Vec3& p : profile.points) w.vec(p);
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
  w.str("device");
  w.str(device);
  w.str("commit");
  w.str(commit);
  return std::move(w.bytes());
}

std::string serialise_pile(const PileBuild& pile, const std::string& key) {
  Writer w;
  for (char c : kMagic) w.u8(static_cast<std::uint8_t>(c));
  w.u32(kPileFormatVersion);
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
  w.vec(pile.bounds.lo);
  w.vec(pile.bounds.hi);
  // the container
  w.u64(pile.geoms.size());
  for (const StaticGeom& g : pile.geoms) {
    w.u8(g.type == StaticGeom::Type::Box ? 1 : 0);
    w.vec(g.centre);
    for (int c = 0; c < 3; ++c) w.vec(g.axes.col(c));
    w.vec(g.half);
  }
  // the particles, array by array as Particles stores them
  const Particles& p = pile.particles;
  const std::size_t n = p.size();
  if (p.velocity.size() != n || p.omega.size() != n || p.rotation.size() != n ||
      p.radius.size() != n || p.inv_mass.size() != n || p.inv_inertia.size() != n)
    throw Error("serialise_pile: the particles' arrays differ in length");
  w.u64(n);
  for (const Vec3& v : p.position) w.vec(v);
  for (const Vec3& v : p.velocity) w.vec(v);
  for (const Vec3& v : p.omega) w.vec(v);
  for (const Eigen::Vector4d& q : p.rotation)
    for (int k = 0; k < 4; ++k) w.f64(q[k]);
  for (double v : p.radius) w.f64(v);
  for (double v : p.inv_mass) w.f64(v);
  for (double v : p.inv_inertia) w.f64(v);
  // the checksum of everything before it
  w.u64(fnv1a64(w.bytes()));
  return std::move(w.bytes());
}

PileBuild parse_pile(const std::string& bytes, const std::string& where, std::string* key) {
  // the header first: a file of another kind or version is named as such, not as corrupt
  if (bytes.size() < kMagic.size() ||
      bytes.compare(0, kMagic.size(), kMagic.data(), kMagic.size()) != 0)
    throw InputError(where + ": not a talus pile file (no 'TALUSPIL' at its start)");
  Reader head(bytes, bytes.size(), where);
  for (std::size_t k = 0; k < kMagic.size(); ++k) head.u8("magic");
  const std::uint32_t version = head.u32("format version");
  if (version != kPileFormatVersion)
    throw InputError(where + ": pile format version " + std::to_string(version) +
                     ", this talus reads " + std::to_string(kPileFormatVersion) +
                     "; delete the file, the pile is built again");
  if (bytes.size() < kMagic.size() + 4 + 8)
    throw InputError(
        where +
        ": the file ends inside its checksum (truncated); delete it, the pile is built again");
  const std::size_t body = bytes.size() - 8;
  Reader tail(std::string_view(bytes).substr(body), 8, where);
  if (tail.u64("checksum") != fnv1a64(bytes.substr(0, body)))
    throw InputError(
        where +
        ": the checksum does not match (truncated or corrupt); delete it, the pile is built again");

  Reader r(bytes, body, where);
  for (std::size_t k = 0; k < kMagic.size(); ++k) r.u8("magic");
  r.u32("format version");
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
  pile.bounds.lo = r.vec("bounds");
  pile.bounds.hi = r.vec("bounds");
  // counts are checked against the bytes left before anything is allocated
  const std::uint64_t geoms = r.u64("geoms");
  r.need(geoms <= r.left() / kGeomBytes ? geoms * kGeomBytes : r.left() + 1, "geoms");
  pile.geoms.resize(geoms);
  for (StaticGeom& g : pile.geoms) {
    g.type = r.u8("geoms") != 0 ? StaticGeom::Type::Box : StaticGeom::Type::Plane;
    g.centre = r.vec("geoms");
    for (int c = 0; c < 3; ++c) g.axes.col(c) = r.vec("geoms");
    g.half = r.vec("geoms");
  }
  const std::uint64_t n = r.u64("particles");
  r.need(n <= r.left() / kParticleBytes ? n * kParticleBytes : r.left() + 1, "particles");
  Particles& p = pile.particles;
  p.position.resize(n);
  p.velocity.resize(n);
  p.omega.resize(n);
  p.rotation.resize(n);
  p.radius.resize(n);
  p.inv_mass.resize(n);
  p.inv_inertia.resize(n);
  for (Vec3& v : p.position) v = r.vec("particles");
  for (Vec3& v : p.velocity) v = r.vec("particles");
  for (Vec3& v : p.omega) v = r.vec("particles");
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
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open the pile file (does it exist, may you read it?)");
  std::ostringstream bytes;
  bytes << in.rdbuf();
  return parse_pile(bytes.str(), path, key);
}

std::string default_cache_dir() {
  // the XDG base directory specification's order, with talus's own variable first
  if (const char* dir = std::getenv("TALUS_CACHE_DIR"); dir && *dir) return dir;
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg)
    return (std::filesystem::path(xdg) / "talus").string();
  if (const char* home = std::getenv("HOME"); home && *home)
    return (std::filesystem::path(home) / ".cache" / "talus").string();
  return "";
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
