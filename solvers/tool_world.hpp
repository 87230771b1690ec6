// Rigid tools in the particle world: bodies that touch the particles through a triangle mesh but
// are not part of the wheel loader — the blade of the cutting test, the moving ring and the
// loading platen of the shear box (issue 11, terrain/shear_test and terrain/cutting_test).
//
// A tool is the bucket of the coupled step without the vehicle behind it. Its contacts come from
// the same Embree closest-point queries (solvers/bucket_contacts), its rows are the same bucket
// rows (solvers/bucket_rows), solved on the device by the same kernel after every particle sweep;
// only the mobility W that the vehicle's direct solve gives the bucket is the tool's own:
//   - kinematic (W = 0): the motion is prescribed, the particles cannot push the tool; the rows'
//     impulses are the force the drive must supply (the cutting blade, the shear ring, the
//     bucket of the type-G terrain, which the machine moves and the particles only feel). A
//     kinematic tool may turn: its orientation and angular velocity are prescribed too;
//   - loaded (W = 1/M on the axes the tool may move along): a body of mass M, pulled by an
//     external force (a platen's weight) and pushed by the particles within the same sweeps, so
//     the coupling is as strong as the bucket's. A loaded tool translates only: W's angular rows
//     must be zero and it has no prescribed turn (a platen held level by its frame, a blade on
//     rails); only a kinematic tool turns.
// Each tool is swept after the particle rows, one after another in index order, so a step is
// deterministic like every other. When every tool is kinematic, the particles' rows against them
// do not depend on one another across particles: they are solved a particle at a time (each
// particle's rows in that same order) inside the particle sweeps' launch
// (solvers/kinematic_tool_rows), with the serial walk's results; a loaded tool's rows stay one
// chain per tool, after every sweep.
#pragma once
#include <memory>
#include <vector>

#include "host/device.hpp"
#include "solvers/bucket_contacts.hpp"
#include "solvers/bucket_rows.hpp"
#include "solvers/bucket_selection.hpp"
#include "solvers/dem_world.hpp"
#include "solvers/embree.hpp"
#include "solvers/kinematic_tool_rows.hpp"
#include "vehicle/bucket_mesh.hpp"

namespace talus {

// appends a closed box (12 triangles, outward faces) with centre `centre` and half extents `half`,
// in the mesh's own frame; the shell contacts of solvers/bucket_contacts make it solid from outside
void add_box(vehicle::BucketMesh& mesh, const Vec3& centre, const Vec3& half);

struct Tool {
  vehicle::BucketMesh mesh;        // the triangles, in the tool's frame (profile and volumes unused)
  Vec3 position = Vec3::Zero();    // of the tool's frame origin in the world [m]; arms are taken about it
  Vec3 velocity = Vec3::Zero();    // of the tool [m/s]
  // the mesh frame's orientation in the world, and its angular velocity [1/s] (prescribed; a
  // loaded tool keeps omega zero, as its mobility cannot turn it)
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
  Vec3 omega = Vec3::Zero();
  // response to an impulse wrench about the origin (twist change per [N s; N m s]): zero for a
  // kinematic tool, 1/M on the free axes of a loaded one; the angular rows must be zero
  Mat6 mobility = Mat6::Zero();
  Vec3 external_force = Vec3::Zero();  // [N], moves a loaded tool through its mobility (its weight)
  BucketMaterial material;
};

// what the particles did to one tool in the last step
struct ToolLoad {
  Vec6 wrench = Vec6::Zero();      // mean wrench on the tool about its origin over the step [N, N m]
  int contacts = 0;                // particle-tool contact rows
  double max_overlap_rel = 0.0;    // deepest overlap at the step's start, in particle radii
};

class ToolWorld {
 public:
  // `dem` must outlive the world; throws InputError for a negative material coefficient or a
  // mobility that would turn the tool, talus::Error (from BucketScene) for a mesh with no usable
  // triangle
  ToolWorld(Device& dev, DemWorld& dem, std::vector<Tool> tools, const embree::Device& embree = embree::Device());
  ~ToolWorld();

  // one particle step with the tools' rows solved inside every sweep, then both sides move
  void step();

  // the tools' memory of last step's contact impulses follows the particles' renumbering
  // (DemWorld::renumber_particles: new_index_of_old[k] is particle k's new index, -1 if gone, the
  // survivors in their order), so the survivors' tool contacts keep their warm start
  void renumber_particles(const std::vector<int>& new_index_of_old);

  // the state a step carries to the next (digging/saved_state): per tool its pose and twist (a
  // loaded tool moves itself), last step's contact impulses (the warm start) and load.
  // restore_state reads it into a world made with the same tools over a DemWorld restored first
  // (the impulses name its particles); InputError for another number of tools or a bad entry
  void save_state(ByteWriter& w) const;
  void restore_state(ByteReader& r);

  size_t size() const;
  // the tools; a kinematic tool's velocity may be changed between steps (its prescribed motion)
  Tool& tool(size_t i);
  const Tool& tool(size_t i) const;
  const ToolLoad& load(size_t i) const;
  DemWorld& dem() { return dem_; }

 private:
  struct Side;
  Device& dev_;
  DemWorld& dem_;
  std::vector<std::unique_ptr<Side>> sides_;
  // the rows of every tool when all are kinematic, solved a particle at a time
  std::unique_ptr<KinematicToolRows> kinematic_;
};

}  // namespace talus
