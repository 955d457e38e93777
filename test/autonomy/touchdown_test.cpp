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

// Where nothing says where the surface is (a failsafe descent onto whatever lies below), any
// impact counts, as before; re-arming forgets the contact height.
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

}  // namespace
}  // namespace alight::autonomy
