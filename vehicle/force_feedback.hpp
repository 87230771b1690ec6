// Force-feedback bucket filling (SPEC §5, paper §7): the admittance-style controller that sets the
// boom (lift) and bucket (tilt) cylinder target speeds from the boom cylinder force, and the full
// loading cycle around it:
//   approach  at 8 km/h with the bucket flat on the ground, until the bucket reaches the pile;
//   fill      drive on at 8 km/h; v_bm = u_bm v_bm,max and v_bk = u_bk v_bk,max with
//             u_bm = clip(k_bm (f_bm - δ_bm), 0, 1), u_bk = clip(k_bk (f_bm - δ_bk), 0, 1), until the
//             bucket tip breaks out of the pile;
//   hold      0.5 s still, for the soil to settle;
//   retreat   reverse at 8 km/h while lifting and tilting to boom -20° and bucket 50°;
//   done      back at the starting point.
// The parameters a = [δ_bm, k_bm, δ_bk, k_bk] follow the paper's search line a(s) = a0 + (a1 - a0) s.
#pragma once
#include <string>
#include <utility>
#include <vector>

#include "vehicle/sensors.hpp"

namespace talus::vehicle {

// a = [δ_bm, k_bm, δ_bk, k_bk]: thresholds on the normalised boom force and gains
struct FeedbackGains {
  double boom_threshold = 0.0, boom_gain = 0.0, bucket_threshold = 0.0, bucket_gain = 0.0;
};

// the paper's search line: a0 = [0.7, 0.3, 0.2, 0.2], a1 = [0.0, 2.2, 0.15, 4.8]; s in [0, 1]
// (InputError outside)
FeedbackGains gains_on_search_line(double s);

// the fractions of the cylinders' top speeds, u_bm and u_bk, for a normalised boom force
std::pair<double, double> feedback_response(const FeedbackGains& a, double boom_force);

enum class CyclePhase { Approach, Fill, Hold, Retreat, Done };
const char* phase_name(CyclePhase p);

struct CycleSettings {
  double drive_speed = 8.0 / 3.6;   // [m/s] approach and retreat, paper §7.1
  double hold_time = 0.5;           // [s] still after breakout, paper §7.1
  double final_boom_deg = -20.0;    // boom and bucket angles to reach while reversing, paper §7.1
  double final_bucket_deg = 50.0;
  double boom_force_scale = 0.0;    // [N] f_bm = f_lift / scale: both lift cylinders at full push
  double lift_max_speed = 0.0;      // [m/s] v_bm,max
  double tilt_max_speed = 0.0;      // [m/s] v_bk,max
  // breakout: the tip, having been buried this deep below the pile's initial surface, rises this
  // far above it [m] (a tenth of a metre: half a D200 grain, far below the bucket's 1.2 m height)
  double breakout_margin = 0.1;
  double max_fill_time = 15.0;      // [s] a fill that never breaks out ends here (the cycle goes on)
};

struct CycleTargets {
  double drive = 0.0, lift = 0.0, tilt = 0.0;  // target speeds [m/s]
};

class FeedbackCycle {
 public:
  // `surface`: the pile's initial surface as (x, z) points, x increasing (the laser scan);
  // `toe_x`: where the bucket reaches the pile; `start_x`: the machine's starting position
  // (the x_vehicle sensor); InputError for impossible settings
  FeedbackCycle(const FeedbackGains& gains, const CycleSettings& settings, std::vector<std::pair<double, double>> surface,
                double toe_x, double start_x);

  // the targets for the next step, from the sensors after the last one: advance, then targets
  CycleTargets update(const SensorSample& s);
  // the phase changes the sensors after the last step call for (a caller that commands the fill
  // itself advances the cycle, then asks for the targets of the other phases)
  void advance(const SensorSample& s);
  // the phase's targets for these sensors: the force-feedback controller's in the fill
  CycleTargets targets(const SensorSample& s) const;
  CyclePhase phase() const { return phase_; }
  bool done() const { return phase_ == CyclePhase::Done; }
  // whether the fill ended by the bucket breaking out of the pile (not by its time limit)
  bool broke_out() const { return broke_out_; }
  // when each phase began [s] (-1 when not reached)
  double phase_start(CyclePhase p) const { return starts_[static_cast<int>(p)]; }
  // the pile's initial surface height at x [m] (linear between scan points, 0 before the first)
  double surface_at(double x) const;
  // where the cycle is, for a saved state (digging/saved_state): the phase, when each began and
  // what the fill found; the gains, settings and surface are the constructor's, not saved
  void save_state(ByteWriter& w) const;
  void restore_state(ByteReader& r);

 private:
  void enter(CyclePhase p, double t);

  FeedbackGains gains_;
  CycleSettings settings_;
  std::vector<std::pair<double, double>> surface_;
  double toe_x_, start_x_;
  CyclePhase phase_ = CyclePhase::Approach;
  double starts_[5] = {0.0, -1.0, -1.0, -1.0, -1.0};
  bool buried_ = false, broke_out_ = false;
};

}  // namespace talus::vehicle
