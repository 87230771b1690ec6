// Ray-traced pictures of a digging run: the particles as spheres, triangle meshes (the bucket)
// and a ground plane, shaded with one directional light, ambient light and shadow rays, traced
// with Embree 3 (spheres as RTC_GEOMETRY_TYPE_SPHERE_POINT, meshes as triangles). The result is
// a talus::Image for Image::write_png.
//
// Conventions. World frame as in the SPEC: x forward, y left, z up, metres. Image rows run top to
// bottom. Colours are display (sRGB) values in [0, 1]; shading scales them directly, one ray per
// pixel unless `supersample` asks for more. Embree decides which primitive a ray hits; the hit
// point and normal are then recomputed in double from the caller's data.
//
// Determinism. Rays are traced in a fixed order on the calling thread and every sample's colour
// is a pure function of the input, so the same input gives the same pixels.
#pragma once
#include <array>
#include <optional>
#include <vector>

#include "io/image.hpp"
#include "solvers/embree.hpp"
#include "solvers/particles.hpp"
#include "terrain/voxel_terrain.hpp"

namespace talus {

struct BucketPose;
namespace vehicle {
struct BucketMesh;
}

// a display colour, each channel in [0, 1]
struct Colour {
  double r = 0.0, g = 0.0, b = 0.0;
};

// matplotlib's viridis ramp (perceptually uniform, readable in greyscale), t in [0, 1] clamped:
// linear interpolation between nine stops sampled at t = 0, 1/8, ..., 1
Colour viridis(double t);

// a triangle mesh in world coordinates with one flat colour; shaded from both sides
struct RenderMesh {
  std::vector<Vec3> vertices;                 // world [m]
  std::vector<std::array<int, 3>> triangles;  // indices into vertices
  Colour colour{0.90, 0.68, 0.10};            // machine yellow
};

// the type-G terrain's surface as a mesh: the column centres at their surface heights, two
// triangles between every four (the piecewise-linear surface of terrain/heightmap)
RenderMesh terrain_mesh(const VoxelTerrain& terrain, const Colour& colour);

// the bucket mesh (profile frame) posed into the world: vertices pose.to_world(v), same triangles
RenderMesh posed_mesh(const vehicle::BucketMesh& mesh, const BucketPose& pose,
                      const Colour& colour = RenderMesh().colour);

enum class ParticleColouring {
  Uniform,  // particle_colour
  Height,   // viridis over the centre height z in [height_lo, height_hi]
  Speed,    // viridis over |v| in [0, max_speed]
};

struct RenderScene {
  // not owned, must outlive render_particles; nullptr (or no particles) draws none
  const Particles* particles = nullptr;
  ParticleColouring colouring = ParticleColouring::Height;
  Colour particle_colour{0.55, 0.45, 0.33};  // uniform mode: gravel brown
  // height ramp [m]; when height_hi <= height_lo the range is the free particles' centre heights
  double height_lo = 0.0, height_hi = 0.0;
  double max_speed = 1.0;                   // [m/s] speed at the top of the ramp
  Colour fixed_colour{0.60, 0.60, 0.60};    // particles with inv_mass == 0
  std::vector<RenderMesh> meshes;
  std::optional<double> ground_height;      // z of a ground plane [m]; solid below it
  Colour ground_colour{0.80, 0.77, 0.70};
  Colour background{1.0, 1.0, 1.0};
  // direction towards the light (need not be unit): from above, the viewer's side (-y) and -x,
  // so the side view is lit from the upper left and the tops of the pile read brightest
  Vec3 light_towards = Vec3(-0.4, -0.6, 1.0);
  double ambient = 0.3;                     // fraction of the colour a surface keeps in shadow
  bool shadows = true;                      // shadow rays (rtcOccluded1) towards the light
  int supersample = 1;                      // n × n samples per pixel on a regular grid, averaged
};

struct Camera {
  enum class Projection { Orthographic, Perspective };
  Projection projection = Projection::Orthographic;
  Vec3 eye = Vec3(0.0, -10.0, 0.0);  // perspective: the eye; orthographic: centre of the image plane
  Vec3 forward = Vec3(0.0, 1.0, 0.0);  // view direction (need not be unit)
  Vec3 up = Vec3(0.0, 0.0, 1.0);       // roughly up in the image; must not be parallel to forward
  double view_height = 4.0;            // orthographic: world height the image spans [m]
  double fov_y_deg = 35.0;             // perspective: vertical field of view [deg], in (0, 180)
};

// the world box of the particles (centre ± radius) and mesh vertices; the ground is not
// included. An empty scene gives lo = hi = 0.
Bounds render_bounds(const RenderScene& scene);

// orthographic side view looking along +y (x to the right, z up) that fits the box [lo, hi] with
// `margin` (fraction of the larger fitted extent) on every side, for an image of width / height =
// `aspect`. The image plane sits in front of the box (y below lo.y). A box smaller than 1 mm is
// shown 1 m high, so an empty scene still renders. Throws talus::InputError for lo > hi,
// non-finite corners, aspect <= 0 or margin < 0.
Camera side_camera(const Vec3& lo, const Vec3& hi, double aspect = 2.0, double margin = 0.05);

// perspective view from the right (-y), above and, for positive azimuth, behind (-x): azimuth 0
// is the side view (looking along +y); positive azimuth swings the eye towards -x so it also
// looks along +x, the digging direction; elevation tilts it down from above.
// The eye looks at the box centre from far enough back that every corner of the box lies inside
// the view with `margin` to spare (as in side_camera: the box's projection fits a view shrunk by
// 1 / (1 + 2 margin)). Throws talus::InputError like side_camera, and for elevation outside
// (-90, 90) or fov_y_deg outside (0, 180).
Camera three_quarter_camera(const Vec3& lo, const Vec3& hi, double aspect = 2.0, double azimuth_deg = 35.0,
                            double elevation_deg = 25.0, double fov_y_deg = 35.0, double margin = 0.05);

// ray-traces the scene into a width × height image. Shading: colour × (ambient + (1 − ambient)
// max(0, n·l) s), s = 0 when a shadow ray towards the light hits anything, else 1. Throws
// talus::InputError for width or height <= 0, a bad camera, supersample < 1, ambient outside
// [0, 1], a zero light direction, max_speed <= 0 in speed mode, non-finite positions, radius <= 0
// or mesh indices out of range; talus::Error for Embree failures.
Image render_particles(const RenderScene& scene, const Camera& camera, int width, int height,
                       const embree::Device& device = embree::Device());

}  // namespace talus
