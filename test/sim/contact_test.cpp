#include <gtest/gtest.h>

#include <cmath>

#include "sim/simulator.hpp"
#include "sim_test_util.hpp"

namespace alight::sim {
namespace {

using test::hover;
using test::place;

struct Outcome {
  Truth truth;
  int max_contact = 0;
};

// Descends from 30 cm above the platform top at the given offset (in the platform's frame),
// cuts the motors at the first touch (as the autonomy does on the accelerometer spike), then
// waits for the vehicle to settle.
Outcome land(const std::string& scenario_name, const Vector2d& offset_P, double yaw = 0.0) {
  const Scenario sc = test::quiet(test::scenario(scenario_name));
  const VehicleParams v = test::starmac();
  Simulator sim(sc, v, 1);
  const PlatformTruth p = *sim.truth().platform;
  const Vector3d off_W =
      rotation_from_rpy(0, 0, p.yaw_rad) * Vector3d(offset_P.x(), offset_P.y(), 0);
  place(sim, p.top_center_W + off_W + Vector3d(0, 0, v.gear_height_m + 0.3), true, yaw);
  AttitudeCommand cmd = hover(v);
  cmd.thrust_N *= 0.9;
  Outcome out;
  for (int ms = 0; ms < 5000; ++ms) {
    if (sim.truth().contact != Contact::kNone) cmd.armed = false;
    sim.step(cmd, sim.now_utime() + 1000);
    out.max_contact = std::max(out.max_contact, static_cast<int>(sim.truth().contact));
  }
  out.truth = sim.truth();
  return out;
}

TEST(SimContactTest, ACentredLandingRestsOnEachOfThePapersPlatforms) {
  for (const char* name : {"landing_a", "landing_b", "landing_c"}) {
    SCOPED_TRACE(name);
    const Outcome o = land(name, Vector2d(0, 0));
    EXPECT_TRUE(o.truth.landed);
    EXPECT_FALSE(o.truth.tipped);
    EXPECT_EQ(o.truth.contact, Contact::kPlatformTop);
    EXPECT_FALSE(o.truth.state.armed);
    const double expected_z = o.truth.platform->top_center_W.z() + test::starmac().gear_height_m;
    EXPECT_NEAR(o.truth.state.p_W_B.z(), expected_z, 0.005);
  }
}

TEST(SimContactTest, AnOffsetLandingWithTheGearStillOnTopRests) {
  // Platform a is 43.2 cm long; the 15 cm gear still fits 5 cm off centre, also turned.
  const Outcome o = land("landing_a", Vector2d(0.05, 0.03), 0.3);
  EXPECT_TRUE(o.truth.landed);
  EXPECT_FALSE(o.truth.tipped);
}

TEST(SimContactTest, ALandingOffsetByMoreThanHalfThePlatformFails) {
  struct Case {
    const char* scenario;
    Vector2d offset;
  };
  for (const Case& c :
       {Case{"landing_a", Vector2d(0.26, 0.0)}, Case{"landing_b", Vector2d(0.0, 0.17)},
        Case{"landing_c", Vector2d(0.14, 0.0)}, Case{"landing_c", Vector2d(-0.12, 0.16)}}) {
    SCOPED_TRACE(std::string(c.scenario) + " offset " + std::to_string(c.offset.x()) + ", " +
                 std::to_string(c.offset.y()));
    const Outcome o = land(c.scenario, c.offset);
    EXPECT_FALSE(o.truth.landed);
    EXPECT_TRUE(o.truth.tipped);
    // Off the top: fallen to the floor or leaning on the platform's edge, not sitting level.
    const double tilt = std::acos(o.truth.state.q_WB.toRotationMatrix()(2, 2));
    const bool below_top = o.truth.state.p_W_B.z() < o.truth.platform->top_center_W.z();
    EXPECT_TRUE(tilt > 0.5 || below_top) << "tilt " << tilt << " z " << o.truth.state.p_W_B.z();
  }
}

TEST(SimContactTest, GearHalfOverTheEdgeTipsOff) {
  // Centre of mass still over the top, two feet past the edge: it must not rest there.
  const Outcome o = land("landing_c", Vector2d(0.09, 0.0));
  EXPECT_FALSE(o.truth.landed);
  EXPECT_TRUE(o.truth.tipped);
}

TEST(SimContactTest, ALandingOnTheFloorIsNotALandingOnThePlatform) {
  const Scenario sc = test::quiet(test::scenario("landing_none"));
  Simulator sim(sc, test::starmac(), 1);
  AttitudeCommand off;
  sim.step(off, sim.now_utime() + 1000000);
  EXPECT_EQ(sim.truth().contact, Contact::kFloor);
  EXPECT_FALSE(sim.truth().landed);
  EXPECT_FALSE(sim.truth().tipped);
  EXPECT_NEAR(sim.state().p_W_B.z(), test::starmac().gear_height_m, 0.005);
}

Outcome fly_at_wall(const std::string& scenario_name, const VehicleParams& v, double y_m) {
  Simulator sim(test::quiet(test::scenario(scenario_name)), v, 1);
  place(sim, Vector3d(2.0, y_m, 1.2));
  VehicleState s = sim.state();
  s.v_W_B = Vector3d(1.0, 0, 0);
  sim.set_state(s);
  Outcome out;
  for (int ms = 0; ms < 2500; ++ms) {
    sim.step(hover(v), sim.now_utime() + 1000);
    out.max_contact = std::max(out.max_contact, static_cast<int>(sim.truth().contact));
  }
  out.truth = sim.truth();
  return out;
}

TEST(SimContactTest, FlyingIntoTheSolidWallIsACollision) {
  const Outcome o = fly_at_wall("ingress_solid", test::starmac(), 0.0);
  EXPECT_TRUE(o.truth.collided);
  EXPECT_GE(o.truth.n_collisions, 1);
  EXPECT_EQ(o.max_contact, static_cast<int>(Contact::kWall));
  EXPECT_LT(o.truth.state.p_W_B.x(), 3.0);  // did not pass through
}

TEST(SimContactTest, ASmallVehicleThroughTheOpeningsCentreDoesNotCollide) {
  VehicleParams small = test::starmac();
  small.arm_length_m = 0.12;
  small.rotor_tip_span_m = 0.4;
  const Outcome o = fly_at_wall("ingress", small, 0.0);
  EXPECT_FALSE(o.truth.collided);
  EXPECT_GT(o.truth.state.p_W_B.x(), 3.5);  // through, into the room
}

TEST(SimContactTest, ClippingTheOpeningsFrameIsACollision) {
  VehicleParams small = test::starmac();
  small.arm_length_m = 0.12;
  small.rotor_tip_span_m = 0.4;
  const Outcome o = fly_at_wall("ingress", small, 0.2);  // rotor tip 10 cm into the frame
  EXPECT_TRUE(o.truth.collided);
  EXPECT_EQ(o.max_contact, static_cast<int>(Contact::kFrame));
}

TEST(SimContactTest, TheFullSizeStarmacDoesNotFitThePapersOpening) {
  // 75 cm rotor-tip span against a 60 cm opening: the paper stopped short of the fly-through.
  const Outcome o = fly_at_wall("ingress", test::starmac(), 0.0);
  EXPECT_TRUE(o.truth.collided);
}

}  // namespace
}  // namespace alight::sim
