#include <gtest/gtest.h>
#include <cstdio>
#include "host/device.hpp"
#include "host/stage_times.hpp"
#include "solvers/dem_world.hpp"
#include "terrain/scenes.hpp"
namespace talus {
TEST(Scratch, Profile) {
  Device dev;
  Scene scene = settle10k_scene();
  DemWorld world(dev, scene.material, scene.settings, scene.bounds, scene.geoms);
  world.set_particles(scene.particles);
  StageTimes times;
  for (int i = 0; i < 1000; ++i) {
    if (i == 400) dev.set_stage_times(&times);
    world.step();
  }
  dev.finish();
  for (auto& [n, t] : times.totals()) std::printf("%-20s %.3f ms/step\n", n.c_str(), 1e3 * t / 600);
}
}
