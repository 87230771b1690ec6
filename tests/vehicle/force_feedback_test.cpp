// The force-feedback controller and its loading cycle (vehicle/force_feedback): the paper's search
// line, the clipped response law, and the phases driven by sensor samples.
#include "vehicle/force_feedback.hpp"

#include <gtest/gtest.h>

#include "host/error.hpp"

namespace talus::vehicle {
namespace {

TEST(ForceFeedback, SearchLineRunsFromA0ToA1) {
  const FeedbackGains a0 = gains_on_search_line(0.0), a1 = gains_on_search_line(1.0), mid = gains_on_search_line(0.5);
  EXPECT_DOUBLE_EQ(a0.boom_threshold, 0.7);
  EXPECT_DOUBLE_EQ(a0.boom_gain, 0.3);
  EXPECT_DOUBLE_EQ(a0.bucket_threshold, 0.2);
  EXPECT_DOUBLE_EQ(a0.bucket_gain, 0.2);
  EXPECT_DOUBLE_EQ(a1.boom_threshold, 0.0);
  EXPECT_DOUBLE_EQ(a1.boom_gain, 2.2);
  EXPECT_DOUBLE_EQ(a1.bucket_threshold, 0.15);
  EXPECT_DOUBLE_EQ(a1.bucket_gain, 4.8);
  EXPECT_DOUBLE_EQ(mid.boom_gain, 1.25);
  EXPECT_DOUBLE_EQ(mid.bucket_threshold, 0.175);
  EXPECT_THROW(gains_on_search_line(-0.1), InputError);
  EXPECT_THROW(gains_on_search_line(1.5), InputError);
}

TEST(ForceFeedback, ResponseIsClippedLinearAboveTheThresholds) {
  const FeedbackGains a{0.4, 2.0, 0.2, 5.0};
  EXPECT_EQ(feedback_response(a, 0.1), std::make_pair(0.0, 0.0));       // below both thresholds
  EXPECT_EQ(feedback_response(a, 0.3).first, 0.0);                       // boom still below its own
  EXPECT_DOUBLE_EQ(feedback_response(a, 0.3).second, 0.5);               // 5 (0.3 - 0.2)
  EXPECT_DOUBLE_EQ(feedback_response(a, 0.6).first, 0.4);                // 2 (0.6 - 0.4)
  EXPECT_DOUBLE_EQ(feedback_response(a, 0.6).second, 1.0);               // saturated
  EXPECT_EQ(feedback_response(a, 2.0), std::make_pair(1.0, 1.0));
}

// a cycle on a 1 m high pile whose toe is at x = 5 m: (x, z) surface points
std::vector<std::pair<double, double>> test_surface() { return {{5.0, 0.0}, {6.0, 1.0}, {8.0, 1.0}}; }

CycleSettings test_settings() {
  CycleSettings c;
  c.boom_force_scale = 800e3;
  c.lift_max_speed = 0.2;
  c.tilt_max_speed = 0.25;
  return c;
}

SensorSample sample(double t, double tip_x, double tip_z, double x_vehicle, double f_lift = 0.0) {
  SensorSample s;
  s.t = t;
  s.bucket_tip_x = tip_x;
  s.bucket_tip_z = tip_z;
  s.x_vehicle = x_vehicle;
  s.f_lift = f_lift;
  s.boom_deg = -35.0;
  return s;
}

TEST(ForceFeedback, CycleGoesThroughItsPhases) {
  const FeedbackGains a{0.5, 2.0, 0.25, 4.0};
  FeedbackCycle c(a, test_settings(), test_surface(), 5.0, 0.0);
  EXPECT_DOUBLE_EQ(c.surface_at(5.5), 0.5);
  EXPECT_DOUBLE_EQ(c.surface_at(3.0), 0.0);
  EXPECT_DOUBLE_EQ(c.surface_at(20.0), 1.0);
  // approach at 8 km/h, cylinders still
  CycleTargets t = c.update(sample(0.0, 3.5, 0.0, 0.0));
  EXPECT_EQ(c.phase(), CyclePhase::Approach);
  EXPECT_NEAR(t.drive, 8.0 / 3.6, 1e-12);
  EXPECT_EQ(t.lift, 0.0);
  // at the toe: fill, targets from the normalised boom force f_bm = 480 / 800 = 0.6
  t = c.update(sample(2.0, 5.0, 0.0, 1.5, 480e3));
  EXPECT_EQ(c.phase(), CyclePhase::Fill);
  EXPECT_NEAR(t.lift, 0.2 * 0.2, 1e-12);   // u_bm = 2 (0.6 - 0.5)
  EXPECT_NEAR(t.tilt, 0.25 * 1.0, 1e-12);  // u_bk = 4 (0.6 - 0.25), clipped to 1
  EXPECT_NEAR(t.drive, 8.0 / 3.6, 1e-12);
  // above the surface without having been buried: still filling (the toe is not a breakout)
  c.update(sample(2.1, 5.05, 0.3, 1.55));
  EXPECT_EQ(c.phase(), CyclePhase::Fill);
  // buried, then out above the initial surface: hold, everything still
  c.update(sample(3.0, 7.0, 0.2, 3.5));
  EXPECT_EQ(c.phase(), CyclePhase::Fill);
  t = c.update(sample(4.0, 7.0, 1.2, 3.5));
  EXPECT_EQ(c.phase(), CyclePhase::Hold);
  EXPECT_EQ(t.drive, 0.0);
  EXPECT_DOUBLE_EQ(c.phase_start(CyclePhase::Hold), 4.0);
  // after 0.5 s: reverse while lifting and tilting towards boom -20 deg and bucket 50 deg
  t = c.update(sample(4.5, 7.0, 1.2, 3.5));
  EXPECT_EQ(c.phase(), CyclePhase::Retreat);
  EXPECT_NEAR(t.drive, -8.0 / 3.6, 1e-12);
  EXPECT_DOUBLE_EQ(t.lift, 0.2);
  EXPECT_DOUBLE_EQ(t.tilt, 0.25);
  SensorSample there = sample(6.0, 5.0, 1.5, 1.0);
  there.boom_deg = -19.0;
  there.bucket_deg = 51.0;
  t = c.update(there);
  EXPECT_EQ(t.lift, 0.0);
  EXPECT_EQ(t.tilt, 0.0);
  // back at the start: done
  c.update(sample(7.5, 3.4, 1.5, -0.01));
  EXPECT_TRUE(c.done());
  EXPECT_DOUBLE_EQ(c.phase_start(CyclePhase::Done), 7.5);
}

TEST(ForceFeedback, FillThatNeverBreaksOutEndsAtTheTimeLimit) {
  CycleSettings settings = test_settings();
  settings.max_fill_time = 3.0;
  FeedbackCycle c(gains_on_search_line(0.5), settings, test_surface(), 5.0, 0.0);
  c.update(sample(1.0, 5.0, 0.0, 1.5));
  c.update(sample(3.9, 6.5, 0.2, 3.0));
  EXPECT_EQ(c.phase(), CyclePhase::Fill);
  c.update(sample(4.1, 6.5, 0.2, 3.0));
  EXPECT_EQ(c.phase(), CyclePhase::Hold);
}

TEST(ForceFeedback, ImpossibleSettingsAreRejected) {
  CycleSettings bad = test_settings();
  bad.boom_force_scale = 0.0;
  EXPECT_THROW(FeedbackCycle(gains_on_search_line(0.0), bad, test_surface(), 5.0, 0.0), InputError);
  EXPECT_THROW(FeedbackCycle(gains_on_search_line(0.0), test_settings(), {}, 5.0, 0.0), InputError);
  EXPECT_THROW(FeedbackCycle(gains_on_search_line(0.0), test_settings(), {{6.0, 1.0}, {5.0, 0.0}}, 5.0, 0.0),
               InputError);
}

}  // namespace
}  // namespace talus::vehicle
