// io/render: the Embree ray tracer draws spheres where and as big as they are, hides what is
// behind a mesh, shades with shadows, colours by height and speed, fits its cameras, and gives
// the same pixels for the same input.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <random>

#include "host/error.hpp"
#include "io/render.hpp"
#include "solvers/bucket_contacts.hpp"
#include "vehicle/bucket_mesh.hpp"

namespace talus {
namespace {

constexpr double kPi = 3.14159265358979323846;

bool same_pixel(const Image& img, int x, int y, const uint8_t* rgb) {
  const uint8_t* p = img.pixel(x, y);
  return p[0] == rgb[0] && p[1] == rgb[1] && p[2] == rgb[2];
}

bool is_colour(const Image& img, int x, int y, const Colour& c) {
  const uint8_t rgb[3] = {static_cast<uint8_t>(std::lround(c.r * 255)), static_cast<uint8_t>(std::lround(c.g * 255)),
                          static_cast<uint8_t>(std::lround(c.b * 255))};
  return same_pixel(img, x, y, rgb);
}

// the pixel's colour direction (unit vector in rgb): shading scales all channels alike
Vec3 chroma(const uint8_t* p) { return Vec3(p[0], p[1], p[2]).normalized(); }
Vec3 chroma(const Colour& c) { return Vec3(c.r, c.g, c.b).normalized(); }

// one sphere at the origin in a 2 m × 2 m orthographic side view
struct OneSphere {
  static constexpr int kSize = 200;    // pixels, 100 px/m
  static constexpr double kR = 0.5;    // m: 50 px
  Particles particles;
  RenderScene scene;
  Camera camera = side_camera(Vec3(-1, -1, -1), Vec3(1, 1, 1), 1.0, 0.0);
  OneSphere() {
    particles.add(Vec3::Zero(), kR, 2590);
    scene.particles = &particles;
    scene.colouring = ParticleColouring::Uniform;
    scene.particle_colour = Colour{0.1, 0.2, 0.9};
  }
  // distance of pixel (i, j)'s centre from the sphere's image centre [px]
  static double px_from_centre(int i, int j) { return std::hypot(i + 0.5 - kSize / 2, j + 0.5 - kSize / 2); }
};

TEST(Render, SphereCoversItsDiscAndNothingElse) {
  OneSphere s;
  Image img = render_particles(s.scene, s.camera, OneSphere::kSize, OneSphere::kSize);
  const double r_px = OneSphere::kR * OneSphere::kSize / 2.0;
  int lit = 0, stray = 0, holes = 0;
  for (int j = 0; j < img.height(); ++j)
    for (int i = 0; i < img.width(); ++i) {
      const bool bg = is_colour(img, i, j, s.scene.background);
      lit += !bg;
      const double d = OneSphere::px_from_centre(i, j);
      // one pixel of slack for the edge: float rays against a float sphere
      if (d > r_px + 1 && !bg) ++stray;
      if (d < r_px - 1 && bg) ++holes;
    }
  const double expected = kPi * r_px * r_px;
  std::printf("[ render ] sphere r = %.0f px: %d lit pixels, pi r^2 = %.1f (%+.3f %%)\n", r_px, lit, expected,
              100.0 * (lit - expected) / expected);
  EXPECT_NEAR(lit, expected, 0.01 * expected);
  EXPECT_EQ(stray, 0);
  EXPECT_EQ(holes, 0);
}

TEST(Render, SupersampledSphereKeepsItsArea) {
  OneSphere s;
  s.scene.supersample = 3;
  // a black sphere on white: every shade of black is black, so 1 − red / 255 is the pixel's coverage
  s.scene.particle_colour = Colour{0.0, 0.0, 0.0};
  Image img = render_particles(s.scene, s.camera, OneSphere::kSize, OneSphere::kSize);
  double covered = 0.0;
  int blends = 0;
  for (int j = 0; j < img.height(); ++j)
    for (int i = 0; i < img.width(); ++i) {
      const int red = img.pixel(i, j)[0];
      covered += 1.0 - red / 255.0;
      blends += red > 0 && red < 255;
    }
  const double r_px = OneSphere::kR * OneSphere::kSize / 2.0;
  const double expected = kPi * r_px * r_px;
  std::printf("[ render ] supersample 3: summed coverage %.1f px (pi r^2 = %.1f, %+.3f %%), %d edge blends\n",
              covered, expected, 100.0 * (covered - expected) / expected, blends);
  EXPECT_NEAR(covered, expected, 0.005 * expected);
  // edge pixels are blends: about the circumference, 2 pi r, of them
  EXPECT_GT(blends, 2 * kPi * r_px * 0.5);
}

TEST(Render, TriangleBetweenCameraAndSphereHidesIt) {
  OneSphere s;
  // a red square (two triangles) spanning x, z in [-0.8, 0.8], in front (y = -0.8) or behind
  auto square = [](double y) {
    RenderMesh m;
    m.vertices = {Vec3(-0.8, y, -0.8), Vec3(0.8, y, -0.8), Vec3(0.8, y, 0.8), Vec3(-0.8, y, 0.8)};
    m.triangles = {{0, 1, 2}, {0, 2, 3}};
    m.colour = Colour{0.9, 0.1, 0.1};
    return m;
  };
  auto count_blue = [&](const Image& img) {
    int blue = 0;
    for (int j = 0; j < img.height(); ++j)
      for (int i = 0; i < img.width(); ++i) {
        const uint8_t* p = img.pixel(i, j);
        blue += p[2] > p[0] && !is_colour(img, i, j, s.scene.background);
      }
    return blue;
  };
  s.scene.meshes = {square(-0.8)};
  Image front = render_particles(s.scene, s.camera, OneSphere::kSize, OneSphere::kSize);
  s.scene.meshes = {square(0.8)};
  Image behind = render_particles(s.scene, s.camera, OneSphere::kSize, OneSphere::kSize);
  const double r_px = OneSphere::kR * OneSphere::kSize / 2.0;
  const int blue_front = count_blue(front), blue_behind = count_blue(behind);
  std::printf("[ render ] sphere pixels with the square in front: %d, behind: %d (pi r^2 = %.0f)\n", blue_front,
              blue_behind, kPi * r_px * r_px);
  EXPECT_EQ(blue_front, 0);
  EXPECT_NEAR(blue_behind, kPi * r_px * r_px, 0.01 * kPi * r_px * r_px);
  // the centre pixel is the square's red, shaded
  const uint8_t* c = front.pixel(OneSphere::kSize / 2, OneSphere::kSize / 2);
  EXPECT_NEAR(chroma(c).dot(chroma(Colour{0.9, 0.1, 0.1})), 1.0, 1e-3);
}

TEST(Render, FixedParticleIsGrey) {
  Particles p;
  p.add(Vec3(-0.5, 0, 0), 0.3, 2590);
  p.add(Vec3(0.5, 0, 0), 0.3, 2590);
  p.inv_mass[0] = 0.0;
  RenderScene scene;
  scene.particles = &p;
  scene.colouring = ParticleColouring::Speed;
  // x in [-1, 1] over 200 px: the centres at x = -0.5 and 0.5 m fall on columns 50 and 150
  Image img = render_particles(scene, side_camera(Vec3(-1, -1, -0.5), Vec3(1, 1, 0.5), 2.0, 0.0), 200, 100);
  const uint8_t* fixed = img.pixel(50, 50);
  const uint8_t* free = img.pixel(150, 50);
  std::printf("[ render ] fixed particle (%d, %d, %d), free particle (%d, %d, %d)\n", fixed[0], fixed[1], fixed[2],
              free[0], free[1], free[2]);
  EXPECT_EQ(fixed[0], fixed[1]);
  EXPECT_EQ(fixed[1], fixed[2]);
  EXPECT_GT(fixed[0], 0);
  EXPECT_LE(fixed[0], std::lround(255 * scene.fixed_colour.r));
  // the free one at rest is the ramp's low end, far from grey
  EXPECT_NEAR(chroma(free).dot(chroma(viridis(0.0))), 1.0, 1e-3);
}

TEST(Render, ShadowDarkensTheGroundUnderASphere) {
  Particles p;
  p.add(Vec3(0, 0, 1), 0.5, 2590);
  RenderScene scene;
  scene.particles = &p;
  scene.ground_height = 0.0;
  scene.light_towards = Vec3(1, 0, 1);  // 45° from the +x side: the shadow centre lies at (-1, 0, 0)
  // orthographic top view of x, y in [-3, 3]: 50 px/m
  Camera top;
  top.eye = Vec3(0, 0, 5);
  top.forward = Vec3(0, 0, -1);
  top.up = Vec3(0, 1, 0);
  top.view_height = 6.0;
  constexpr int kSize = 300;
  auto pixel_of = [&](double x, double y) {
    return std::pair<int, int>(static_cast<int>((x / 3.0 + 1) * kSize / 2), static_cast<int>((1 - y / 3.0) * kSize / 2));
  };
  Image img = render_particles(scene, top, kSize, kSize);
  const auto [si, sj] = pixel_of(-1.0, 0.0);
  const auto [fi, fj] = pixel_of(2.5, 2.5);
  const double shadow = img.pixel(si, sj)[1], far = img.pixel(fi, fj)[1];
  // lambert: shadow / lit = ambient / (ambient + (1 − ambient) cos 45°)
  const double expected = scene.ambient / (scene.ambient + (1 - scene.ambient) * std::sqrt(0.5));
  std::printf("[ render ] ground green channel in shadow %.0f, far away %.0f: ratio %.4f (lambert %.4f)\n", shadow,
              far, shadow / far, expected);
  EXPECT_NEAR(shadow / far, expected, 0.02 * expected);
  // the far ground is the lit ground colour
  EXPECT_NEAR(far, 255 * scene.ground_colour.g * (scene.ambient + (1 - scene.ambient) * std::sqrt(0.5)), 1.0);
  // without shadow rays the same spot is as bright as the far ground
  scene.shadows = false;
  Image flat = render_particles(scene, top, kSize, kSize);
  EXPECT_EQ(flat.pixel(si, sj)[1], flat.pixel(fi, fj)[1]);
}

TEST(Render, ColourByHeightSpansTheRamp) {
  Particles p;
  for (int k = 0; k < 3; ++k) p.add(Vec3(0, 0, k * 1.0), 0.3, 2590);
  RenderScene scene;
  scene.particles = &p;
  scene.colouring = ParticleColouring::Height;
  constexpr int kW = 100, kH = 300;
  Image img = render_particles(scene, side_camera(Vec3(-0.5, -0.3, -0.5), Vec3(0.5, 0.3, 2.5), 1.0 / 3.0, 0.0), kW,
                               kH);
  // centres at z = 0, 1, 2 m in a view of z in [-0.5, 2.5]: 100 px/m
  const double t[3] = {0.0, 0.5, 1.0};
  for (int k = 0; k < 3; ++k) {
    const uint8_t* c = img.pixel(kW / 2, static_cast<int>((2.5 - k) * 100));
    const double match = chroma(c).dot(chroma(viridis(t[k])));
    std::printf("[ render ] particle at z = %d m: (%d, %d, %d), cos to viridis(%.1f) = %.5f\n", k, c[0], c[1], c[2],
                t[k], match);
    EXPECT_NEAR(match, 1.0, 1e-3);
  }
  // the low and high ends are far apart, so the test can tell them apart
  EXPECT_LT(chroma(viridis(0.0)).dot(chroma(viridis(1.0))), 0.8);
}

TEST(Render, ColourBySpeedClampsAtMax) {
  Particles p;
  for (int k = 0; k < 3; ++k) p.add(Vec3(k * 1.0, 0, 0), 0.3, 2590);
  p.velocity[1] = Vec3(0.6, 0.8, 0);  // |v| = 1 m/s: middle at max 2 m/s
  p.velocity[2] = Vec3(0, 0, -5);     // beyond max: the top
  RenderScene scene;
  scene.particles = &p;
  scene.colouring = ParticleColouring::Speed;
  scene.max_speed = 2.0;
  Image img = render_particles(scene, side_camera(Vec3(-0.5, -0.3, -0.5), Vec3(2.5, 0.3, 0.5), 3.0, 0.0), 300, 100);
  const double t[3] = {0.0, 0.5, 1.0};
  for (int k = 0; k < 3; ++k)
    EXPECT_NEAR(chroma(img.pixel(50 + 100 * k, 50)).dot(chroma(viridis(t[k]))), 1.0, 1e-3) << k;
}

TEST(Render, ViridisStops) {
  // the stops themselves (matplotlib's viridis at 0, 1/2, 1) and clamping
  auto bytes = [](const Colour& c) -> Vec3 { return Vec3(c.r, c.g, c.b) * 255.0; };
  EXPECT_LT((bytes(viridis(0.0)) - Vec3(0x44, 0x01, 0x54)).norm(), 1e-9);
  EXPECT_LT((bytes(viridis(0.5)) - Vec3(0x21, 0x91, 0x8c)).norm(), 1e-9);
  EXPECT_LT((bytes(viridis(1.0)) - Vec3(0xfd, 0xe7, 0x25)).norm(), 1e-9);
  EXPECT_LT((bytes(viridis(-1.0)) - bytes(viridis(0.0))).norm(), 1e-12);
  EXPECT_LT((bytes(viridis(7.0)) - bytes(viridis(1.0))).norm(), 1e-12);
  // lightness (here: the sum of channels) grows monotonically along the ramp
  double prev = -1.0;
  for (int k = 0; k <= 64; ++k) {
    const Colour c = viridis(k / 64.0);
    const double luma = 0.2126 * c.r + 0.7152 * c.g + 0.0722 * c.b;
    EXPECT_GT(luma, prev) << k;
    prev = luma;
  }
}

TEST(Render, EmptySceneIsBackground) {
  RenderScene scene;
  scene.background = Colour{0.2, 0.4, 0.6};
  const Bounds b = render_bounds(scene);
  Image img = render_particles(scene, side_camera(b.lo, b.hi), 64, 32);
  int other = 0;
  for (int j = 0; j < img.height(); ++j)
    for (int i = 0; i < img.width(); ++i) other += !is_colour(img, i, j, scene.background);
  EXPECT_EQ(other, 0);
  EXPECT_EQ(img.pixel(0, 0)[1], 102);
  // an empty particle set and a mesh without triangles draw nothing either
  Particles none;
  scene.particles = &none;
  scene.meshes.push_back(RenderMesh{});
  Image img2 = render_particles(scene, three_quarter_camera(b.lo, b.hi), 64, 32);
  for (int j = 0; j < img2.height(); ++j)
    for (int i = 0; i < img2.width(); ++i) other += !is_colour(img2, i, j, scene.background);
  EXPECT_EQ(other, 0);
}

TEST(Render, BadArgumentsThrowInputError) {
  OneSphere s;
  EXPECT_THROW(render_particles(s.scene, s.camera, 0, 10), InputError);
  EXPECT_THROW(render_particles(s.scene, s.camera, 10, -1), InputError);
  RenderScene bad = s.scene;
  bad.supersample = 0;
  EXPECT_THROW(render_particles(bad, s.camera, 10, 10), InputError);
  bad = s.scene;
  bad.light_towards = Vec3::Zero();
  EXPECT_THROW(render_particles(bad, s.camera, 10, 10), InputError);
  bad = s.scene;
  bad.colouring = ParticleColouring::Speed;
  bad.max_speed = 0.0;
  EXPECT_THROW(render_particles(bad, s.camera, 10, 10), InputError);
  bad = s.scene;
  RenderMesh m;
  m.vertices = {Vec3::Zero(), Vec3::UnitX(), Vec3::UnitZ()};
  m.triangles = {{0, 1, 3}};
  bad.meshes = {m};
  EXPECT_THROW(render_particles(bad, s.camera, 10, 10), InputError);
  Particles p = s.particles;
  p.radius[0] = 0.0;
  bad = s.scene;
  bad.particles = &p;
  EXPECT_THROW(render_particles(bad, s.camera, 10, 10), InputError);
  Camera cam = s.camera;
  cam.up = cam.forward;
  EXPECT_THROW(render_particles(s.scene, cam, 10, 10), InputError);
  cam = s.camera;
  cam.view_height = 0.0;
  EXPECT_THROW(render_particles(s.scene, cam, 10, 10), InputError);
  EXPECT_THROW(side_camera(Vec3(1, 0, 0), Vec3(0, 1, 1)), InputError);
  EXPECT_THROW(side_camera(Vec3::Zero(), Vec3::Ones(), 0.0), InputError);
  EXPECT_THROW(three_quarter_camera(Vec3::Zero(), Vec3::Ones(), 2.0, 35.0, 90.0), InputError);
}

// a heap of ~6,000 particles on a jittered lattice (bottom layer fixed) and the bucket before it
struct Heap {
  Particles particles;
  RenderScene scene;
  Heap() {
    std::mt19937 rng(12345);  // fixed: the picture is part of the determinism check
    std::uniform_real_distribution<double> jitter(-0.01, 0.01), radius(0.045, 0.058);
    constexpr double kD = 0.12;  // m, lattice spacing
    for (int i = 0; i < 45; ++i)
      for (int j = 0; j < 15; ++j) {
        const double x = 0.6 + i * kD, y = -0.84 + j * kD;
        const double top = std::min(1.2, 0.5 * (x - 0.6)) + kD;  // a 27° face and a flat top
        for (int k = 0; k * kD < top; ++k) {
          particles.add(Vec3(x + jitter(rng), y + jitter(rng), 0.06 + k * kD + jitter(rng)), radius(rng), 2590);
          if (k == 0) particles.inv_mass.back() = 0.0;
        }
      }
    scene.particles = &particles;
    scene.ground_height = 0.0;
    BucketPose pose;
    pose.position = Vec3(0.3, 0.0, 0.1);
    scene.meshes.push_back(posed_mesh(vehicle::make_bucket_mesh(vehicle::BucketGeometry{}), pose));
  }
};

// pixels on the image's border that are not background (the camera cut something off)
int border_hits(const Image& img, const Colour& background) {
  int hits = 0;
  for (int i = 0; i < img.width(); ++i)
    hits += !is_colour(img, i, 0, background) + !is_colour(img, i, img.height() - 1, background);
  return hits;
}

TEST(Render, HeapSideViewIsDeterministicAndFits) {
  Heap heap;
  const Bounds b = render_bounds(heap.scene);
  const Camera cam = side_camera(b.lo, b.hi, 2.0);
  constexpr int kW = 1200, kH = 600;
  const auto t0 = std::chrono::steady_clock::now();
  Image a = render_particles(heap.scene, cam, kW, kH);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  Image again = render_particles(heap.scene, cam, kW, kH);
  std::printf("[ render ] %zu particles + bucket + ground, %d x %d side view: %.3f s (%.3f s per megapixel)\n",
              heap.particles.size(), kW, kH, seconds, seconds / (kW * kH * 1e-6));
  int differ = 0;
  for (int j = 0; j < kH; ++j)
    for (int i = 0; i < kW; ++i) differ += !same_pixel(again, i, j, a.pixel(i, j));
  EXPECT_EQ(differ, 0);
  // the box fits: nothing on the top row; the ground fills the bottom rows (z < 0 is below the
  // ground line), and the columns at the left and right edges are background above the ground
  int top_row = 0, side_cols = 0;
  const int ground_row = static_cast<int>(kH / 2.0 + (0.5 * (b.lo.z() + b.hi.z()) / cam.view_height) * kH);
  for (int i = 0; i < kW; ++i) top_row += !is_colour(a, i, 0, heap.scene.background);
  for (int j = 0; j < ground_row - 1; ++j)
    side_cols += !is_colour(a, 0, j, heap.scene.background) + !is_colour(a, kW - 1, j, heap.scene.background);
  EXPECT_EQ(top_row, 0);
  EXPECT_EQ(side_cols, 0);
  const auto path = std::filesystem::temp_directory_path() / "talus_render_side.png";
  a.write_png(path.string());
  EXPECT_TRUE(std::filesystem::exists(path));
}

TEST(Render, HeapThreeQuarterViewFits) {
  Heap heap;
  heap.scene.ground_height.reset();  // the infinite ground would reach the border
  const Bounds b = render_bounds(heap.scene);
  Image img = render_particles(heap.scene, three_quarter_camera(b.lo, b.hi, 2.0), 600, 300);
  int drawn = 0;
  for (int j = 0; j < img.height(); ++j)
    for (int i = 0; i < img.width(); ++i) drawn += !is_colour(img, i, j, heap.scene.background);
  int left_right = 0;
  for (int j = 0; j < img.height(); ++j)
    left_right += !is_colour(img, 0, j, heap.scene.background) + !is_colour(img, img.width() - 1, j, heap.scene.background);
  std::printf("[ render ] three-quarter view: %d of %d pixels drawn\n", drawn, img.width() * img.height());
  EXPECT_EQ(border_hits(img, heap.scene.background) + left_right, 0);
  EXPECT_GT(drawn, img.width() * img.height() / 10);
  // the same with the ground, full size, timed and kept for a look
  heap.scene.ground_height = 0.0;
  const auto t0 = std::chrono::steady_clock::now();
  Image full = render_particles(heap.scene, three_quarter_camera(b.lo, b.hi, 2.0), 1200, 600);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("[ render ] three-quarter view with ground, 1200 x 600: %.3f s\n", seconds);
  full.write_png((std::filesystem::temp_directory_path() / "talus_render_3q.png").string());
}

}  // namespace
}  // namespace talus
