// The pile cache under a dig (digging/digging.cpp's build_scenario_pile through
// terrain/pile_cache): HD27 at D400 dug from a pile read back from the cache steps exactly as from
// the pile it saved, sample for sample and bit for bit.
#include "terrain/pile_cache.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>

#include "digging/digging.hpp"
#include "tests/solvers/dem_test_util.hpp"
#include "vehicle/sensor_channels.hpp"

namespace talus {
namespace {

namespace fs = std::filesystem;

// a double's 64 bits (NaN payloads and the sign of zero included)
std::uint64_t bits_of(double v) {
  std::uint64_t b = 0;
  std::memcpy(&b, &v, sizeof b);
  return b;
}
bool same_bits(double a, double b) { return bits_of(a) == bits_of(b); }

// HD27 at D400 into the pile (2 s of the scenario, its bucket in the gravel): the fresh pile is
// saved, the second build reads it back, and both digs log the same 100 Hz samples and end with
// the same particles
TEST(DiggingPileCache, DigFromACachedPileIsBitIdentical) {
  const fs::path dir =
      fs::temp_directory_path() / ("talus-dig-pile-cache-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  const vehicle::Scenario sc = vehicle::load_scenario("hd27");
  const FidelityPreset& preset = fidelity_preset("D400");
  Device& dev = test::shared_device();
  DiggingOptions options;
  options.pile_cache.enabled = true;
  options.pile_cache.dir = dir.string();
  // a fixed commit: the test's build may be dirty, and the key must not follow it
  options.pile_cache.commit = "0123abc";
  const PileProfile placed = scenario_pile_profile(sc);
  const PileBuild fresh = build_scenario_pile(dev, sc, placed, preset, options, nullptr);
  const PileBuild cached = build_scenario_pile(dev, sc, placed, preset, options, nullptr);
  ASSERT_FALSE(fresh.from_cache);
  ASSERT_TRUE(cached.from_cache);
  EXPECT_EQ(cached.cache_file, fresh.cache_file);

  const int steps = static_cast<int>(std::lround(2.0 / preset.dt));
  DiggingSimulation a(dev, sc, preset, fresh, options);
  DiggingSimulation b(dev, sc, preset, cached, options);
  for (int k = 0; k < steps; ++k) {
    a.step();
    b.step();
  }
  const auto& sa = a.log().samples();
  const auto& sb = b.log().samples();
  ASSERT_EQ(sa.size(), sb.size());
  ASSERT_GT(sa.size(), 100u);
  for (size_t i = 0; i < sa.size(); ++i)
    for (const auto& channel : vehicle::kSensorChannels)
      ASSERT_TRUE(same_bits(sa[i].*channel.field, sb[i].*channel.field))
          << channel.name << " at sample " << i << ": " << sa[i].*channel.field << " vs "
          << sb[i].*channel.field;
  const Particles pa = a.particles(), pb = b.particles();
  ASSERT_EQ(pa.size(), pb.size());
  for (size_t i = 0; i < pa.size(); ++i)
    ASSERT_EQ(pa.position[i], pb.position[i]) << "particle " << i;
  EXPECT_GT(a.split().stats().bucket_contacts, 0);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace talus
