#include "vehicle/force_feedback.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>

#include "host/error.hpp"

namespace talus::vehicle {

namespace {
// the paper's search line end points, a = [δ_bm, k_bm, δ_bk, k_bk] (paper §7.1)
constexpr FeedbackGains kLineStart{0.7, 0.3, 0.2, 0.2};
constexpr FeedbackGains kLineEnd{0.0, 2.2, 0.15, 4.8};
}  // namespace

FeedbackGains gains_on_search_line(double s) {
  if (!(s >= 0.0 && s <= 1.0)) throw InputError("force feedback: search parameter s = " + std::to_string(s) + " is outside [0, 1]");
  auto mix = [s](double a, double b) { return a + (b - a) * s; };
  return {mix(kLineStart.boom_threshold, kLineEnd.boom_threshold), mix(kLineStart.boom_gain, kLineEnd.boom_gain),
          mix(kLineStart.bucket_threshold, kLineEnd.bucket_threshold),
          mix(kLineStart.bucket_gain, kLineEnd.bucket_gain)};
}

std::pair<double, double> feedback_response(const FeedbackGains& a, double boom_force) {
  return {std::clamp(a.boom_gain * (boom_force - a.boom_threshold), 0.0, 1.0),
          std::clamp(a.bucket_gain * (boom_force - a.bucket_threshold), 0.0, 1.0)};
}

const char* phase_name(CyclePhase p) {
  switch (p) {
    case CyclePhase::Approach: return "approach";
    case CyclePhase::Fill: return "fill";
    case CyclePhase::Hold: return "hold";
    case CyclePhase::Retreat: return "retreat";
    case CyclePhase::Done: return "done";
  }
  return "?";
}

FeedbackCycle::FeedbackCycle(const FeedbackGains& gains, const CycleSettings& settings,
                             std::vector<std::pair<double, double>> surface, double toe_x, double start_x)
    : gains_(gains), settings_(settings), surface_(std::move(surface)), toe_x_(toe_x), start_x_(start_x) {
  if (!(settings.boom_force_scale > 0.0) || !(settings.lift_max_speed > 0.0) || !(settings.tilt_max_speed > 0.0) ||
      !(settings.drive_speed > 0.0))
    throw InputError("force feedback: the force scale, the cylinder and drive speeds must be positive");
  if (surface_.empty()) throw InputError("force feedback: the pile's surface has no points (empty scan)");
  if (!std::is_sorted(surface_.begin(), surface_.end()))
    throw InputError("force feedback: the pile's surface points must run in increasing x");
}

double FeedbackCycle::surface_at(double x) const {
  if (x <= surface_.front().first) return 0.0;
  if (x >= surface_.back().first) return surface_.back().second;
  const auto hi = std::upper_bound(surface_.begin(), surface_.end(), std::make_pair(x, -1e300));
  const auto lo = hi - 1;
  const double span = hi->first - lo->first;
  return span > 0.0 ? lo->second + (hi->second - lo->second) * (x - lo->first) / span : hi->second;
}

void FeedbackCycle::enter(CyclePhase p, double t) {
  phase_ = p;
  starts_[static_cast<int>(p)] = t;
}

CycleTargets FeedbackCycle::update(const SensorSample& s) {
  // phase changes first, from the state after the last step
  advance(s);
  return targets(s);
}

void FeedbackCycle::advance(const SensorSample& s) {
  const double height = surface_at(s.bucket_tip_x);
  if (phase_ == CyclePhase::Approach && s.bucket_tip_x >= toe_x_) enter(CyclePhase::Fill, s.t);
  if (phase_ == CyclePhase::Fill) {
    if (s.bucket_tip_z < height - settings_.breakout_margin) buried_ = true;
    broke_out_ = buried_ && s.bucket_tip_z > height + settings_.breakout_margin;
    if (broke_out_ || s.t - phase_start(CyclePhase::Fill) > settings_.max_fill_time)
      enter(CyclePhase::Hold, s.t);
  }
  if (phase_ == CyclePhase::Hold && s.t - phase_start(CyclePhase::Hold) >= settings_.hold_time)
    enter(CyclePhase::Retreat, s.t);
  if (phase_ == CyclePhase::Retreat && s.x_vehicle <= start_x_) enter(CyclePhase::Done, s.t);
}

CycleTargets FeedbackCycle::targets(const SensorSample& s) const {
  CycleTargets c;
  switch (phase_) {
    case CyclePhase::Approach:
      c.drive = settings_.drive_speed;
      break;
    case CyclePhase::Fill: {
      const auto [u_boom, u_bucket] = feedback_response(gains_, s.f_lift / settings_.boom_force_scale);
      c.drive = settings_.drive_speed;
      c.lift = u_boom * settings_.lift_max_speed;
      c.tilt = u_bucket * settings_.tilt_max_speed;
      break;
    }
    case CyclePhase::Hold:
    case CyclePhase::Done:
      break;
    case CyclePhase::Retreat:
      c.drive = -settings_.drive_speed;
      c.lift = s.boom_deg < settings_.final_boom_deg ? settings_.lift_max_speed : 0.0;
      c.tilt = s.bucket_deg < settings_.final_bucket_deg ? settings_.tilt_max_speed : 0.0;
      break;
  }
  return c;
}

void FeedbackCycle::save_state(ByteWriter& w) const {
  w.u8(static_cast<std::uint8_t>(phase_));
  w.f64s(starts_, std::size(starts_));
  w.u8(buried_ ? 1 : 0);
  w.u8(broke_out_ ? 1 : 0);
}

void FeedbackCycle::restore_state(ByteReader& r) {
  const std::uint8_t phase = r.u8("loading cycle");
  if (phase > static_cast<std::uint8_t>(CyclePhase::Done))
    throw InputError(r.where() + ": a loading-cycle phase " + std::to_string(phase) + " (corrupt)");
  phase_ = static_cast<CyclePhase>(phase);
  r.f64s(starts_, std::size(starts_), "loading cycle");
  buried_ = r.u8("loading cycle") != 0;
  broke_out_ = r.u8("loading cycle") != 0;
}

}  // namespace talus::vehicle
