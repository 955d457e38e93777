// Touch-down detection (autonomy/touchdown.hpp): the impact counts only within reach of the
// contact height where that is known.

#include "autonomy/touchdown.hpp"

#include <gtest/gtest.h>

namespace alight::autonomy {
namespace {

ImuSample spike(double excess_mps2) {
  ImuSample imu;
  imu.accel_B = Vector3d(0, 0, 9.81 + excess_mps2);
  return imu;
}

PoseSample at_height(double z_m) {
  PoseSample p;
  p.p_W_B = Vector3d(0, 0, z_m);
  p.v_W_B = Vector3d(0, 0, -0.4);  // descending: not resting
  return p;
}

// PX4 SIH in SITL, position control over landing_c (seeds 10996, 11008, 11020): braking a
// paused final descent from about 0.5 m/s over its noisy IMU put 4.2-5.3 m/s^2 over g into one
// sample with the gear 12-15 cm above the top; the motors were cut and the vehicle fell, twice
// onto the top's edge. With the contact height known that spike is not an impact; the same
// spike at contact is.
TEST(TouchdownDetectorTest, ASpikeWithTheGearStillAboveTheTopIsNoImpact) {
  const LandingParams params;
  const double top_z = 0.219, contact_z = top_z + params.gear_height_m;
  TouchdownDetector td(params);
  td.arm(0);
  td.set_contact_z(contact_z);
  td.add_pose(at_height(contact_z + 0.15), contact_z - 0.1, 1000);
  td.add_imu(spike(params.touchdown_accel_mps2 + 1.27));
  EXPECT_FALSE(td.detected());
  td.add_pose(at_height(contact_z + 0.01), contact_z - 0.1, 2000);
  td.add_imu(spike(params.touchdown_accel_mps2 + 1.27));
  ASSERT_TRUE(td.detected());
  EXPECT_STREQ(td.cue(), "impact");
}

// Told neither where the surface is nor to confirm, any impact counts; re-arming forgets the
// contact height.
TEST(TouchdownDetectorTest, WithoutAContactHeightEveryImpactCounts) {
  const LandingParams params;
  TouchdownDetector td(params);
  td.arm(0);
  td.set_contact_z(0.3);
  td.arm(10);
  td.add_pose(at_height(2.0), 0.0, 1000);
  td.add_imu(spike(params.touchdown_accel_mps2 - 0.1));
  EXPECT_FALSE(td.detected());  // under the threshold
  td.add_imu(spike(params.touchdown_accel_mps2 + 0.1));
  EXPECT_TRUE(td.detected());
}

ImuSample spike_at(double excess_mps2, int64_t utime) {
  ImuSample imu = spike(excess_mps2);
  imu.utime = utime;
  return imu;
}

// A failsafe descent's detector: armed, confirming its impacts.
TouchdownDetector confirming(const LandingParams& params) {
  TouchdownDetector td(params);
  td.arm(0);
  td.confirm_impacts();
  return td;
}

PoseSample moving(double z_m, double vz_mps) {
  PoseSample p = at_height(z_m);
  p.v_W_B.z() = vz_mps;
  return p;
}

// PX4 position SITL over landing_a (seed 11028): every process stalled 2.7 s, motion capture
// went stale, autonomy began its failsafe descent and took a spike in the burst of samples
// after the stall for the touch-down, cutting the motors 1.57 m up while PX4's own failsafe
// threw the vehicle about. A failsafe descent knows no contact height: its impact stands only
// once a pose shows the body stopped.
TEST(TouchdownDetectorTest, AFailsafeImpactStandsOnlyWhenAPoseShowsTheBodyStopped) {
  const LandingParams params;
  const double over = params.touchdown_accel_mps2 + 1.0;
  TouchdownDetector td = confirming(params);
  td.add_imu(spike_at(over, 1'000'000));
  td.add_pose(moving(1.57, -0.6), 0.0, 1'010'000);  // thrown about: still moving
  td.add_pose(moving(1.52, 0.3), 0.0, 1'100'000);
  EXPECT_FALSE(td.detected());
  // The window closes with poses that never showed it stopped: no touch-down.
  td.add_imu(spike_at(0.0, 1'000'000 + static_cast<int64_t>(kImpactConfirmS * 1e6) + 1000));
  td.add_pose(moving(1.40, 0.0), 0.0, 1'600'000);  // hovering later, no new impact
  EXPECT_FALSE(td.detected());
  // On the floor: the impact, then the body at rest.
  td.add_imu(spike_at(over, 5'000'000));
  EXPECT_FALSE(td.detected());
  td.add_pose(moving(0.10, -0.35), 0.0, 5'010'000);
  EXPECT_FALSE(td.detected());
  td.add_pose(moving(0.10, -0.02), 0.0, 5'030'000);
  ASSERT_TRUE(td.detected());
  EXPECT_STREQ(td.cue(), "impact");
}

// A blind descent (no pose at all since the impact) has nothing but the impact to go by.
TEST(TouchdownDetectorTest, ABlindFailsafeDescentTakesTheImpactAlone) {
  const LandingParams params;
  TouchdownDetector td = confirming(params);
  td.add_imu(spike_at(params.touchdown_accel_mps2 + 1.0, 2'000'000));
  td.add_imu(spike_at(0.0, 2'000'000 + static_cast<int64_t>(0.5 * kImpactConfirmS * 1e6)));
  EXPECT_FALSE(td.detected());
  td.add_imu(spike_at(0.0, 2'000'000 + static_cast<int64_t>(kImpactConfirmS * 1e6) + 1000));
  ASSERT_TRUE(td.detected());
  EXPECT_STREQ(td.cue(), "impact");
}

// The final descent knows its contact height; confirming does not delay an impact there.
TEST(TouchdownDetectorTest, ConfirmingLeavesAKnownContactAlone) {
  const LandingParams params;
  TouchdownDetector td = confirming(params);
  td.set_contact_z(0.3);
  td.add_pose(at_height(0.31), 0.2, 1000);
  td.add_imu(spike_at(params.touchdown_accel_mps2 + 1.0, 2000));
  EXPECT_TRUE(td.detected());
}

}  // namespace
}  // namespace alight::autonomy
