// A compliant frictional contact between two bodies (or a body and the world) across a plane whose
// place its owner sets every step: the type-G terrain's aggregate interfaces (issue 14, paper
// §4.4), A between the bucket and the aggregate (the bucket's cutting plane, bucket-soil friction)
// and B between the aggregate and the resting terrain (the failure plane, the soil's internal
// friction).
//
// The contact patch is a fixed number of points on the plane (its corners, say), so that it holds
// torques as a face does, not only forces. Per point, as the ground and tyre contacts
// (vehicle/ground_contact.hpp): a one-sided holonomic normal row (the point's gap g along the
// normal n, which points from body a into body b: b is pushed along +n, a along -n), compliance
// n_points / stiffness (the points share the stiffness) and damping time tau, and two velocity rows
// along the plane with box-linearised Coulomb friction |lambda_t| <= mu lambda_n. The rows are
// there every step; an inactive contact bounds them all to zero force, so the sparsity of the
// vehicle system never changes when the aggregate comes and goes. Each point has its own gap (the
// terrain's support under the bucket, terrain/bucket_support, meets the surface at each point
// apart); a point whose gap is +infinity has nothing under it and carries no force.
#pragma once
#include <vector>

#include "vehicle/constraint.hpp"

namespace talus::vehicle {

struct PlaneContactGeometry {
  bool active = false;
  std::vector<Vec3> points;     // world [m]: as many as the contact was made with
  Vec3 normal = Vec3::UnitZ();  // world, unit, from body a into body b
  // each point's separation along the normal [m], negative = overlap, +infinity = nothing there;
  // as many as points
  std::vector<double> gaps;
};

struct PlaneContactParameters {
  double stiffness = 1.0e6;          // [N/m] of the whole patch
  double damping_time = 0.05;        // [s]
  double friction = 0.0;             // mu
  double viscous_compliance = 1e-9;  // [m/(N s)] of the friction rows
};

class PlaneContact : public Constraint {
 public:
  // body indices of the system, or kWorld for either side; a patch of `points` points (at least 1);
  // throws talus::Error as set_parameters
  PlaneContact(int body_a, int body_b, int points, PlaneContactParameters p);
  // throws talus::Error when the geometry has another number of points or gaps than the contact,
  // or a gap that is NaN or -infinity
  void set_geometry(const PlaneContactGeometry& g);
  int points() const { return points_; }
  // throws talus::Error for a stiffness that is not positive and finite
  void set_parameters(const PlaneContactParameters& p);
  const PlaneContactGeometry& geometry() const { return g_; }
  const PlaneContactParameters& parameters() const { return p_; }
  void add_rows(const std::vector<RigidBody>& bodies, std::vector<ConstraintRow>& rows) override;
  // of the last solve: the patch's normal force, and its whole force on body b in the world [N]
  double normal_force() const;
  Vec3 force_on_b() const;

 private:
  int a_, b_, points_;
  PlaneContactParameters p_;
  PlaneContactGeometry g_;
  Mat3 frame_ = Mat3::Identity();  // the rows' directions of the last assembly: tangents, normal
};

}  // namespace talus::vehicle
