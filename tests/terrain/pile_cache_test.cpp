// terrain/pile_cache: the settled pile's file (exact round trip, refused when of another version,
// short or corrupt), its key, where the cache lives and how a cached build uses it. Every test
// keeps its files in a temporary folder of its own (never the home cache).
#include "terrain/pile_cache.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include "host/error.hpp"
#include "tests/host/scoped_env.hpp"
#include "tests/host/temp_dir.hpp"
#include "tests/solvers/dem_test_util.hpp"

namespace talus {
namespace {

namespace fs = std::filesystem;

using test::ScopedEnv;
using test::TempDir;

// a double's 64 bits (NaN payloads and the sign of zero included)
std::uint64_t bits_of(double v) {
  std::uint64_t b = 0;
  std::memcpy(&b, &v, sizeof b);
  return b;
}
bool same_bits(double a, double b) { return bits_of(a) == bits_of(b); }
bool same_bits(const Vec3& a, const Vec3& b) {
  return same_bits(a.x(), b.x()) && same_bits(a.y(), b.y()) && same_bits(a.z(), b.z());
}

// every field the file carries, bit for bit
void expect_identical(const PileBuild& a, const PileBuild& b) {
  EXPECT_TRUE(same_bits(a.fill_time, b.fill_time));
  EXPECT_EQ(a.fill_at_rest, b.fill_at_rest);
  EXPECT_TRUE(same_bits(a.fill_rms_speed, b.fill_rms_speed));
  EXPECT_TRUE(same_bits(a.settle_time, b.settle_time));
  EXPECT_EQ(a.at_rest, b.at_rest);
  EXPECT_TRUE(same_bits(a.rms_speed, b.rms_speed));
  EXPECT_EQ(a.settle_iterations, b.settle_iterations);
  EXPECT_TRUE(same_bits(a.bulk_density, b.bulk_density));
  EXPECT_TRUE(same_bits(a.toe_shift, b.toe_shift));
  EXPECT_TRUE(same_bits(a.soil_fit.rms_m, b.soil_fit.rms_m));
  EXPECT_TRUE(same_bits(a.soil_fit.mean_m, b.soil_fit.mean_m));
  EXPECT_TRUE(same_bits(a.bounds.lo, b.bounds.lo));
  EXPECT_TRUE(same_bits(a.bounds.hi, b.bounds.hi));
  ASSERT_EQ(a.geoms.size(), b.geoms.size());
  for (size_t g = 0; g < a.geoms.size(); ++g) {
    EXPECT_EQ(a.geoms[g].type, b.geoms[g].type);
    EXPECT_TRUE(same_bits(a.geoms[g].centre, b.geoms[g].centre));
    EXPECT_TRUE(same_bits(a.geoms[g].half, b.geoms[g].half));
    for (int c = 0; c < 3; ++c)
      EXPECT_TRUE(same_bits(Vec3(a.geoms[g].axes.col(c)), Vec3(b.geoms[g].axes.col(c))));
  }
  const Particles& p = a.particles;
  const Particles& q = b.particles;
  ASSERT_EQ(p.size(), q.size());
  for (size_t i = 0; i < p.size(); ++i) {
    ASSERT_TRUE(same_bits(p.position[i], q.position[i])) << "particle " << i;
    ASSERT_TRUE(same_bits(p.velocity[i], q.velocity[i])) << "particle " << i;
    ASSERT_TRUE(same_bits(p.omega[i], q.omega[i])) << "particle " << i;
    for (int k = 0; k < 4; ++k)
      ASSERT_TRUE(same_bits(p.rotation[i][k], q.rotation[i][k])) << "particle " << i;
    ASSERT_TRUE(same_bits(p.radius[i], q.radius[i])) << "particle " << i;
    ASSERT_TRUE(same_bits(p.inv_mass[i], q.inv_mass[i])) << "particle " << i;
    ASSERT_TRUE(same_bits(p.inv_inertia[i], q.inv_inertia[i])) << "particle " << i;
  }
}

// a small pile made by hand, for the file's error paths (no device needed)
PileBuild hand_made_pile() {
  PileBuild pile;
  pile.particles.add(Vec3(0.1, 0.2, 0.3), 0.2, 2590.0);
  pile.particles.add(Vec3(-0.0, 1.0 / 3.0, 0.7), 0.21, 2590.0);
  pile.particles.velocity[1] = Vec3(1e-300, -2.5, 0.0);
  pile.geoms.push_back(StaticGeom::plane(Vec3::Zero(), Vec3::UnitZ()));
  pile.geoms.push_back(
      StaticGeom::box(Vec3(1, 2, 3), Vec3(0.5, 0.5, 0.5), Eigen::Matrix3d::Identity()));
  pile.bounds = {Vec3(-1, -2, 0), Vec3(4, 2, 5)};
  pile.fill_time = 0.5;
  pile.at_rest = true;
  pile.settle_iterations = 100;
  pile.soil_fit.mean_m = -0.1;
  return pile;
}

// a small container of gravel (2 m wide, 1 m high, 1 m flat top) that builds in a moment at D400
PileProfile small_profile() {
  PileProfile p;
  p.name = "small";
  p.width = 2.0;
  p.points = {Vec3(0, 0, 0), Vec3(1.2, 0, 1.0), Vec3(2.2, 0, 1.0)};
  p.rear_wall_x = 2.2;
  return p;
}

// the lines a cached build tells
struct Notes {
  std::vector<std::string> lines;
  bool any_contains(const std::string& s) const {
    for (const auto& l : lines)
      if (l.find(s) != std::string::npos) return true;
    return false;
  }
};

PileCacheOptions cache_options(Notes& notes, const std::string& dir = "") {
  PileCacheOptions c;
  c.enabled = true;
  c.dir = dir;
  // a fixed commit: the test's build may be dirty, and the key must not follow it
  c.commit = "0123abc";
  c.note = [&notes](const std::string& line) { notes.lines.push_back(line); };
  return c;
}

// the default pile at D400 (SPEC §2.5) through the file and back: every number and array bit
// for bit, and the key with it
TEST(PileCache, RoundTripOfAD400PileIsBitIdentical) {
  const PileProfile profile = default_pile_profile();
  const FidelityPreset& preset = fidelity_preset("D400");
  const PileBuild built = build_pile(test::shared_device(), profile, preset, gravel(), {}, nullptr);
  ASSERT_GT(built.particles.size(), 500u);
  const std::string key = pile_key_bytes(profile, preset, gravel(), {}, "device", "commit");
  TempDir dir("talus-pile-roundtrip");
  const std::string file = (dir.path() / "d400.pile").string();
  write_pile(file, built, key);
  std::string stored;
  const PileBuild back = read_pile(file, &stored);
  EXPECT_EQ(stored, key);
  expect_identical(built, back);
  // and the bytes of the pile read back are the bytes written
  EXPECT_EQ(serialise_pile(back, key), serialise_pile(built, key));
}

// the hand-made pile's odd doubles (a negative zero, a denormal-range number) survive too
TEST(PileCache, RoundTripKeepsEveryBit) {
  const PileBuild pile = hand_made_pile();
  const PileBuild back = parse_pile(serialise_pile(pile, "k"), "mem");
  expect_identical(pile, back);
  EXPECT_TRUE(std::signbit(back.particles.position[1].x()));
}

// whatever decides the pile changes its key; the same inputs give the same key
TEST(PileCache, KeyFollowsEveryInput) {
  const PileProfile profile = small_profile();
  const FidelityPreset& d400 = fidelity_preset("D400");
  const Material soil = gravel();
  const PileBuildOptions options;
  const auto key = [&](const PileProfile& p, const FidelityPreset& f, const Material& m,
                       const PileBuildOptions& o, const std::string& dev = "cpu",
                       const std::string& commit = "abc") {
    return pile_key_name(pile_key_bytes(p, f, m, o, dev, commit));
  };
  const std::string base = key(profile, d400, soil, options);
  EXPECT_EQ(base.size(), 16u);
  EXPECT_EQ(base, key(profile, d400, soil, options));
  // the profile's name and path are not its content
  PileProfile renamed = profile;
  renamed.name = "other";
  renamed.path = "/elsewhere.json";
  EXPECT_EQ(base, key(renamed, d400, soil, options));

  PileBuildOptions seeded = options;
  seeded.seed = 2;
  EXPECT_NE(base, key(profile, d400, soil, seeded));
  EXPECT_NE(base, key(profile, fidelity_preset("D200"), soil, options));
  FidelityPreset finer_dt = d400;
  finer_dt.dt *= 0.5;
  EXPECT_NE(base, key(profile, finer_dt, soil, options));
  Material rolling = soil;
  rolling.rolling = 0.05;
  EXPECT_NE(base, key(profile, d400, rolling, options));
  Material cohesive = soil;
  cohesive.cohesion = 100.0;
  EXPECT_NE(base, key(profile, d400, cohesive, options));
  PileProfile moved = profile;
  moved.points[1].x() += 0.01;
  EXPECT_NE(base, key(moved, d400, soil, options));
  PileProfile wider = profile;
  wider.width += 0.5;
  EXPECT_NE(base, key(wider, d400, soil, options));
  PileBuildOptions unplaced = options;
  unplaced.place_toe = false;
  EXPECT_NE(base, key(profile, d400, soil, unplaced));
  PileBuildOptions free_face = options;
  free_face.hold_face = false;
  EXPECT_NE(base, key(profile, d400, soil, free_face));
  // the sweeps it settles with count as they are resolved: 15 at D400 by the rule or asked for
  PileBuildOptions swept = options;
  swept.settle_iterations = 15;
  EXPECT_EQ(base, key(profile, d400, soil, swept));
  swept.settle_iterations = 200;
  EXPECT_NE(base, key(profile, d400, soil, swept));
  PileBuildOptions formed = free_face;
  formed.form_speed = 0.5;
  EXPECT_NE(key(profile, d400, soil, free_face), key(profile, d400, soil, formed));
  EXPECT_NE(base, key(profile, d400, soil, options, "gpu"));
  EXPECT_NE(base, key(profile, d400, soil, options, "cpu", "abd"));
}

// a file of another version, a short one, a changed byte and another kind of file are each
// refused naming the file and what is wrong
TEST(PileCache, WrongVersionShortOrCorruptFileIsRefused) {
  const std::string good = serialise_pile(hand_made_pile(), "key");
  const auto refusal = [](const std::string& bytes) {
    try {
      parse_pile(bytes, "/cache/x.pile");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  std::string other_version = good;
  other_version[8] = static_cast<char>(kPileFormatVersion + 1);
  std::string msg = refusal(other_version);
  EXPECT_NE(msg.find("/cache/x.pile"), std::string::npos) << msg;
  EXPECT_NE(msg.find("version " + std::to_string(kPileFormatVersion + 1)), std::string::npos)
      << msg;

  for (size_t cut : {size_t{3}, size_t{14}, good.size() / 2, good.size() - 1}) {
    msg = refusal(good.substr(0, cut));
    EXPECT_NE(msg, "accepted") << "cut at " << cut;
    EXPECT_NE(msg.find("/cache/x.pile"), std::string::npos) << msg;
  }
  std::string flipped = good;
  flipped[good.size() / 2] = static_cast<char>(flipped[good.size() / 2] ^ 0x10);
  msg = refusal(flipped);
  EXPECT_NE(msg.find("checksum"), std::string::npos) << msg;
  msg = refusal("{\"not\": \"a pile\"}");
  EXPECT_NE(msg.find("not a talus pile"), std::string::npos) << msg;
  EXPECT_THROW(read_pile("/nonexistent/talus/x.pile"), InputError);
}

// a cached build in $TALUS_CACHE_DIR: a miss builds and saves, the next build reads the same pile
// back; a damaged file is a miss that is built and replaced
TEST(PileCache, BuildSavesThenReadsBackAndRebuildsADamagedFile) {
  TempDir dir("talus-pile-cache");
  ScopedEnv env("TALUS_CACHE_DIR", dir.path().c_str());
  const PileProfile profile = small_profile();
  const FidelityPreset& preset = fidelity_preset("D400");
  Device& dev = test::shared_device();
  Notes notes;
  const PileCacheOptions cache = cache_options(notes);

  const PileBuild first = build_pile_cached(dev, profile, preset, gravel(), {}, cache, nullptr);
  EXPECT_FALSE(first.from_cache);
  const std::string file = first.cache_file;
  EXPECT_EQ(fs::path(file).parent_path(), dir.path() / "piles");
  EXPECT_EQ(fs::path(file).extension(), ".pile");
  ASSERT_TRUE(fs::exists(file));
  EXPECT_TRUE(notes.any_contains("pile saved to cache " + file));

  const PileBuild second = build_pile_cached(dev, profile, preset, gravel(), {}, cache, nullptr);
  EXPECT_TRUE(second.from_cache);
  EXPECT_EQ(second.cache_file, file);
  EXPECT_TRUE(notes.any_contains("pile from cache " + file));
  expect_identical(first, second);

  // another seed is another file
  PileBuildOptions seeded;
  seeded.seed = 7;
  const PileBuild other = build_pile_cached(dev, profile, preset, gravel(), seeded, cache, nullptr);
  EXPECT_FALSE(other.from_cache);
  EXPECT_NE(other.cache_file, file);

  // the file cut short: a note naming it, a fresh build, the file whole again
  fs::resize_file(file, fs::file_size(file) / 2);
  notes.lines.clear();
  const PileBuild rebuilt = build_pile_cached(dev, profile, preset, gravel(), {}, cache, nullptr);
  EXPECT_FALSE(rebuilt.from_cache);
  EXPECT_TRUE(notes.any_contains(file)) << (notes.lines.empty() ? "" : notes.lines[0]);
  EXPECT_TRUE(build_pile_cached(dev, profile, preset, gravel(), {}, cache, nullptr).from_cache);
  // no temporary file is left beside the piles
  for (const auto& entry : fs::directory_iterator(dir.path() / "piles"))
    EXPECT_EQ(entry.path().extension(), ".pile") << entry.path();
}

// a folder that cannot be made (a file stands in its way) is a note; the pile is built all the
// same. A dirty build and a disabled cache touch no file
TEST(PileCache, UnwritableFolderOnlyWarnsAndDirtyBuildsSkipTheCache) {
  TempDir dir("talus-pile-unwritable");
  const fs::path blocker = dir.path() / "a-file";
  std::ofstream(blocker) << "in the way";
  const PileProfile profile = small_profile();
  const FidelityPreset& preset = fidelity_preset("D400");
  Device& dev = test::shared_device();
  Notes notes;
  const PileBuild pile = build_pile_cached(dev, profile, preset, gravel(), {},
                                           cache_options(notes, blocker.string()), nullptr);
  EXPECT_GT(pile.particles.size(), 0u);
  EXPECT_FALSE(pile.from_cache);
  EXPECT_TRUE(pile.cache_file.empty());
  EXPECT_TRUE(notes.any_contains("not saved")) << (notes.lines.empty() ? "" : notes.lines[0]);

  notes.lines.clear();
  const fs::path folder = dir.path() / "cache";
  PileCacheOptions dirty = cache_options(notes, folder.string());
  dirty.commit = "0123abc-dirty";
  EXPECT_FALSE(build_pile_cached(dev, profile, preset, gravel(), {}, dirty, nullptr).from_cache);
  EXPECT_TRUE(notes.any_contains("uncommitted changes"));
  PileCacheOptions off = cache_options(notes, folder.string());
  off.enabled = false;
  EXPECT_FALSE(build_pile_cached(dev, profile, preset, gravel(), {}, off, nullptr).from_cache);
  EXPECT_FALSE(fs::exists(folder));
}

}  // namespace
}  // namespace talus
