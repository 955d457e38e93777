#include "sim/sensor_gate.hpp"

#include <gtest/gtest.h>

#include <limits>

namespace alight::sim {
namespace {

constexpr int64_t kT0 = 1'790'000'000'000'000;

sim_control_t request(double mocap, double camera, double imu) {
  sim_control_t m{};
  m.utime = kT0;
  m.mocap_off_s = mocap;
  m.camera_off_s = camera;
  m.imu_off_s = imu;
  return m;
}

TEST(SensorGateTest, SilencesASensorForTheRequestedSimTime) {
  SensorGates g;
  EXPECT_TRUE(g.mocap.on(kT0));
  ASSERT_FALSE(g.apply(request(0.5, -1, -1), kT0));
  EXPECT_FALSE(g.mocap.on(kT0));
  EXPECT_FALSE(g.mocap.on(kT0 + 499'999));
  EXPECT_TRUE(g.mocap.on(kT0 + 500'000));
  EXPECT_TRUE(g.camera.on(kT0));  // negative: left as it was
  EXPECT_TRUE(g.imu.on(kT0));
}

TEST(SensorGateTest, ZeroResumesAndMaxIsForGood) {
  SensorGates g;
  ASSERT_FALSE(g.apply(request(-1, sim_control_t::MAX_OFF_S, -1), kT0));
  EXPECT_FALSE(g.camera.on(kT0 + 3600LL * 1'000'000));
  ASSERT_FALSE(g.apply(request(-1, 0, -1), kT0 + 10));
  EXPECT_TRUE(g.camera.on(kT0 + 10));
}

TEST(SensorGateTest, NonFiniteOrTooLongRequestsAreRefusedWhole) {
  SensorGates g;
  EXPECT_TRUE(g.apply(request(2, std::numeric_limits<double>::quiet_NaN(), -1), kT0));
  EXPECT_TRUE(g.apply(request(2, -1, std::numeric_limits<double>::infinity()), kT0));
  EXPECT_TRUE(g.apply(request(2, -1, 2e6), kT0));
  EXPECT_TRUE(g.mocap.on(kT0));  // nothing of a refused request applied
}

}  // namespace
}  // namespace alight::sim
