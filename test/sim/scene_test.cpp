#include "sim/scene.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>

#include "common/params.hpp"
#include "sim/sim_msgs.hpp"
#include "sim/simulator.hpp"
#include "sim_test_util.hpp"

namespace alight::sim {
namespace {

using test::place;

double rotor_radius(const std::string& vehicle) {
  return 0.5 *
         load_vehicle_params(test::config_path("vehicles/" + vehicle + ".yaml")).rotor_tip_span_m;
}

// Bug: landing_b with seed 5 put the platform under the vehicle's rotors at the start spot, so
// the sim flagged the vehicle "tipped" before it took off.
TEST(SimSceneTest, RegressionSeededPlatformNeverCoversTheStartSpot) {
  const double largest_rotor_radius = std::max(rotor_radius("starmac"), rotor_radius("pelican"));
  for (const char* name : {"landing_a", "landing_b", "landing_c"}) {
    SCOPED_TRACE(name);
    const Scenario sc = test::scenario(name);
    ASSERT_GT(sc.randomize.platform_xy_m, 0.0);  // the scenario does randomise the platform
    EXPECT_GE(sc.randomize.start_clearance_m, largest_rotor_radius);
    std::set<double> xs;
    for (uint64_t seed = 0; seed < 3000; ++seed) {
      const SeededLayout l = draw_layout(sc, seed);
      const double d = footprint_distance_m(*sc.platform, l.platform_center_xy_m,
                                            l.platform_yaw_rad, sc.start_position_m.head<2>());
      ASSERT_GE(d, sc.randomize.start_clearance_m) << "seed " << seed;
      // Still within the configured ranges.
      ASSERT_LE((l.platform_center_xy_m - sc.platform->center_xy_m).cwiseAbs().maxCoeff(),
                sc.randomize.platform_xy_m + 1e-12);
      ASSERT_LE(std::abs(l.platform_yaw_rad * 180 / M_PI - sc.platform->yaw_deg),
                sc.randomize.platform_yaw_deg + 1e-9);
      xs.insert(l.platform_center_xy_m.x());
    }
    EXPECT_GT(xs.size(), 2900u);  // and still random, not pinned to the nominal placement
  }
  // The reported case, through the whole simulator: resting at the start for a second.
  const VehicleParams v = test::starmac();
  Simulator sim(test::scenario("landing_b"), v, 5);
  const Vector2d start = sim.state().p_W_B.head<2>();
  EXPECT_GE(
      footprint_distance_m(*sim.scenario().platform, sim.truth().platform->top_center_W.head<2>(),
                           sim.truth().platform->yaw_rad, start),
      0.5 * v.rotor_tip_span_m);
  sim.step(AttitudeCommand{}, sim.now_utime() + 1'000'000);
  EXPECT_FALSE(sim.truth().tipped);
  EXPECT_EQ(sim.truth().contact, Contact::kFloor);
}

TEST(SimSceneTest, ANominalPlatformOverTheStartOrAClearanceBelowTheRotorsIsRejected) {
  Scenario sc = test::scenario("landing_a");
  sc.platform->center_xy_m = Vector2d(0.3, 0.0);  // its edge 8 cm from the start
  try {
    sc.validate();
    FAIL() << "no error";
  } catch (const ParamError& e) {
    EXPECT_EQ(e.key(), "platform.center_xy_m");
  }
  sc = test::scenario("landing_a");
  sc.randomize.start_clearance_m = 0.2;  // less than the STARMAC's 0.375 m rotor-tip radius
  EXPECT_NO_THROW(sc.validate());
  try {
    Simulator sim(sc, test::starmac(), 1);
    FAIL() << "no error";
  } catch (const ParamError& e) {
    EXPECT_EQ(e.key(), "randomize.start_clearance_m");
    EXPECT_NE(std::string(e.what()).find("starmac"), std::string::npos) << e.what();
  }
}

TEST(SimSceneTest, SeededLightingIsDeterministicVariedAndMild) {
  const Scenario sc = test::scenario("landing_a");
  ASSERT_GT(sc.randomize.light_falloff, 0.0);
  std::set<double> falloffs, lamp_x, turns;
  for (uint64_t seed = 0; seed < 200; ++seed) {
    const SeededLayout a = draw_layout(sc, seed), b = draw_layout(sc, seed);
    EXPECT_EQ(a.lighting.falloff, b.lighting.falloff);
    EXPECT_EQ(a.lighting.lamp_W, b.lighting.lamp_W);
    EXPECT_EQ(a.lighting.light_dir_W, b.lighting.light_dir_W);
    EXPECT_EQ(a.lighting.gain, b.lighting.gain);
    EXPECT_GE(a.lighting.falloff, 0.0);
    EXPECT_LE(a.lighting.falloff, sc.randomize.light_falloff);
    // The lamp hangs above the flying area at the configured height.
    EXPECT_LE((a.lighting.lamp_W.head<2>() - sc.area_center_xy_m).cwiseAbs().maxCoeff(),
              0.5 * sc.area_size_m.maxCoeff());
    EXPECT_EQ(a.lighting.lamp_W.z(), sc.lighting.lamp_W.z());
    // The light turns about z only, within its range.
    const Vector3d d0 = sc.lighting.light_dir_W, d1 = a.lighting.light_dir_W;
    EXPECT_NEAR(d1.z(), d0.z(), 1e-12);
    const double turn =
        std::atan2(d0.x() * d1.y() - d0.y() * d1.x(), d0.head<2>().dot(d1.head<2>()));
    EXPECT_LE(std::abs(turn) * 180 / M_PI, sc.randomize.light_dir_deg + 1e-9);
    falloffs.insert(a.lighting.falloff);
    lamp_x.insert(a.lighting.lamp_W.x());
    turns.insert(turn);
  }
  EXPECT_EQ(falloffs.size(), 200u);
  EXPECT_EQ(lamp_x.size(), 200u);
  EXPECT_EQ(turns.size(), 200u);

  // Mild: across what the camera sees from 1.5 m (about 1.4 x 1.1 m of floor) the light changes
  // by a few per cent per 10 cm at most, however the seed places the lamp.
  for (uint64_t seed = 0; seed < 50; ++seed) {
    Scene scene;
    scene.lighting = draw_layout(sc, seed).lighting;
    double worst_per_dm = 0;
    for (double x = -3; x <= 3; x += 0.1)
      for (double y = -3; y <= 3; y += 0.1) {
        const double a = scene.illumination(Vector3d(x, y, 0));
        const double b = scene.illumination(Vector3d(x + 0.1, y, 0));
        const double c = scene.illumination(Vector3d(x, y + 0.1, 0));
        worst_per_dm = std::max({worst_per_dm, std::abs(b - a) / a, std::abs(c - a) / a});
      }
    EXPECT_LT(worst_per_dm, 0.03) << "seed " << seed;
  }
}

TEST(SimSceneTest, LeavingTheFlyingAreaIsReportedAndStaysReported) {
  const Scenario sc = test::quiet(test::scenario("landing_none"));
  const VehicleParams v = test::starmac();
  {
    // Hovering anywhere inside, up to just below the ceiling: not flagged.
    Simulator sim(sc, v, 1);
    for (const Vector3d& p :
         {Vector3d(0, 0, 1), Vector3d(2.8, -2.8, 1.5), Vector3d(-2.8, 2.8, 3.8)}) {
      place(sim, p);
      sim.step(test::hover(v), sim.now_utime() + 200'000);
      EXPECT_FALSE(sim.truth().out_of_area) << p.transpose();
    }
  }
  for (const Vector3d& vel : {Vector3d(1, 0, 0), Vector3d(0, -1, 0), Vector3d(0, 0, 1)}) {
    SCOPED_TRACE(vel.transpose());
    Simulator sim(sc, v, 1);
    // 20 cm inside the edge (or below the ceiling), drifting out at 1 m/s.
    const Vector3d p = Vector3d(0, 0, 1.5) + vel.cwiseProduct(Vector3d(2.8, 2.8, 2.3));
    place(sim, p);
    VehicleState s = sim.state();
    s.v_W_B = vel;
    sim.set_state(s);
    sim.step(test::hover(v), sim.now_utime() + 100'000);
    EXPECT_FALSE(sim.truth().out_of_area);
    sim.step(test::hover(v), sim.now_utime() + 400'000);
    EXPECT_TRUE(sim.truth().out_of_area);
    EXPECT_TRUE(to_msg(sim.truth()).out_of_area);
    place(sim, Vector3d(0, 0, 1));  // back inside: the run has still failed
    sim.step(test::hover(v), sim.now_utime() + 100'000);
    EXPECT_TRUE(sim.truth().out_of_area);
  }
  {
    // Ingress: the room behind the opening is part of the flying area.
    Simulator sim(test::quiet(test::scenario("ingress")), v, 1);
    place(sim, Vector3d(4.5, 0, 1.2));
    sim.step(test::hover(v), sim.now_utime() + 200'000);
    EXPECT_FALSE(sim.truth().out_of_area);
  }
}

// Known answers of Scene::cast_ray (what the rangefinder sees).
TEST(SimSceneTest, ARayMeetsTheFloorAtTheKnownDistance) {
  const Scene scene = build_scene(test::quiet(test::scenario("landing_none")), 1);
  auto hit = scene.cast_ray(Vector3d(0.3, -0.2, 2.0), Vector3d(0, 0, -1), 10.0);
  ASSERT_TRUE(hit);
  EXPECT_NEAR(hit->distance_m, 2.0, 1e-12);
  EXPECT_EQ(hit->box, -1);
  EXPECT_TRUE(hit->normal_W.isApprox(Vector3d::UnitZ()));
  // Tilted by 30 deg: 2 / cos 30; the direction's length does not matter.
  const double a = 30.0 * M_PI / 180.0;
  hit = scene.cast_ray(Vector3d(0, 0, 2.0), 5.0 * Vector3d(0, std::sin(a), -std::cos(a)), 10.0);
  ASSERT_TRUE(hit);
  EXPECT_NEAR(hit->distance_m, 2.0 / std::cos(a), 1e-12);
  // Out of reach: pointing up, level, or farther than max_distance_m.
  EXPECT_FALSE(scene.cast_ray(Vector3d(0, 0, 2.0), Vector3d(0, 0.1, 1), 100.0));
  EXPECT_FALSE(scene.cast_ray(Vector3d(0, 0, 2.0), Vector3d(1, 0, 0), 100.0));
  EXPECT_FALSE(scene.cast_ray(Vector3d(0, 0, 2.0), Vector3d(0, 0, -1), 1.999));
  // Below the floor: blocked at once.
  hit = scene.cast_ray(Vector3d(0, 0, -0.01), Vector3d(0, 0, -1), 10.0);
  ASSERT_TRUE(hit);
  EXPECT_EQ(hit->distance_m, 0.0);
  // Not a ray.
  EXPECT_FALSE(scene.cast_ray(Vector3d(0, 0, 2.0), Vector3d::Zero(), 10.0));
  EXPECT_FALSE(scene.cast_ray(Vector3d(0, 0, 2.0), Vector3d(0, 0, NAN), 10.0));
  EXPECT_FALSE(scene.cast_ray(Vector3d(NAN, 0, 2.0), Vector3d(0, 0, -1), 10.0));
  EXPECT_FALSE(scene.cast_ray(Vector3d(0, 0, 2.0), Vector3d(0, 0, -1), NAN));
}

TEST(SimSceneTest, ARayOverThePlatformMeetsItsTopAndPastItsEdgeTheFloor) {
  // landing_a unrandomised: 43.2 x 27.9 x 10.9 cm, centred at (1.0, 0.5), not turned.
  const Scene scene = build_scene(test::quiet(test::scenario("landing_a")), 1);
  const Vector3d down(0, 0, -1);
  auto hit = scene.cast_ray(Vector3d(1.0, 0.5, 1.5), down, 10.0);
  ASSERT_TRUE(hit);
  EXPECT_NEAR(hit->distance_m, 1.5 - 0.109, 1e-12);
  EXPECT_EQ(hit->box, 0);
  EXPECT_TRUE(hit->normal_W.isApprox(Vector3d::UnitZ()));
  // A millimetre inside and outside the edges along x and y.
  for (const Vector2d& in : {Vector2d(1.0 + 0.215, 0.5), Vector2d(1.0 - 0.215, 0.5),
                             Vector2d(1.0, 0.5 + 0.1385), Vector2d(1.0, 0.5 - 0.1385)}) {
    hit = scene.cast_ray(Vector3d(in.x(), in.y(), 1.5), down, 10.0);
    ASSERT_TRUE(hit);
    EXPECT_NEAR(hit->distance_m, 1.5 - 0.109, 1e-12) << in.transpose();
  }
  for (const Vector2d& out : {Vector2d(1.0 + 0.217, 0.5), Vector2d(1.0 - 0.217, 0.5),
                              Vector2d(1.0, 0.5 + 0.1405), Vector2d(1.0, 0.5 - 0.1405)}) {
    hit = scene.cast_ray(Vector3d(out.x(), out.y(), 1.5), down, 10.0);
    ASSERT_TRUE(hit);
    EXPECT_NEAR(hit->distance_m, 1.5, 1e-12) << out.transpose();
    EXPECT_EQ(hit->box, -1);
  }
  // Level, at 5 cm, towards the platform's near side (x = 1.0 - 0.216).
  hit = scene.cast_ray(Vector3d(0.0, 0.5, 0.05), Vector3d(1, 0, 0), 10.0);
  ASSERT_TRUE(hit);
  EXPECT_NEAR(hit->distance_m, 0.784, 1e-12);
  EXPECT_TRUE(hit->normal_W.isApprox(-Vector3d::UnitX()));
  // Slanting down across the edge: the side face, not the top, is met first below its rim.
  hit = scene.cast_ray(Vector3d(0.684, 0.5, 0.15), Vector3d(1, 0, -1), 10.0);
  ASSERT_TRUE(hit);
  EXPECT_NEAR(hit->distance_m, 0.1 * std::sqrt(2.0), 1e-12);  // at x = 0.784, z = 0.05
  EXPECT_TRUE(hit->normal_W.isApprox(-Vector3d::UnitX()));
  // From inside the box: blocked.
  hit = scene.cast_ray(Vector3d(1.0, 0.5, 0.05), down, 10.0);
  ASSERT_TRUE(hit);
  EXPECT_EQ(hit->distance_m, 0.0);
  EXPECT_EQ(hit->box, 0);
}

TEST(SimSceneTest, ARayMeetsATurnedBoxOnTheFaceItReaches) {
  Scene scene;
  Box b;
  b.center_W = Vector3d(0, 0, 0.5);
  b.half_size_m = Vector3d(0.5, 0.5, 0.5);
  b.set_yaw(M_PI / 4);
  scene.boxes.push_back(b);
  // Along +x at y = 0.1: the face whose local y is +0.5 (x + y = ... in world: -x + y = 0.5
  // sqrt(2)), at x = 0.1 - 0.5 sqrt(2).
  const auto hit = scene.cast_ray(Vector3d(-2, 0.1, 0.5), Vector3d(1, 0, 0), 10.0);
  ASSERT_TRUE(hit);
  EXPECT_NEAR(hit->distance_m, 2.0 + 0.1 - 0.5 * std::sqrt(2.0), 1e-12);
  EXPECT_TRUE(hit->normal_W.isApprox(Vector3d(-1, 1, 0).normalized()));
  // Down onto its top from above a corner region still inside the turned footprint.
  const auto top = scene.cast_ray(Vector3d(0.6, 0.0, 2.0), Vector3d(0, 0, -1), 10.0);
  ASSERT_TRUE(top);
  EXPECT_NEAR(top->distance_m, 1.0, 1e-12);  // 0.6 < 0.5 sqrt(2): over the top
  const auto past = scene.cast_ray(Vector3d(0.6, 0.2, 2.0), Vector3d(0, 0, -1), 10.0);
  ASSERT_TRUE(past);
  EXPECT_NEAR(past->distance_m, 2.0, 1e-12);  // 0.6 + 0.2 > 0.5 sqrt(2): the floor
}

TEST(SimSceneTest, ALevelRayMeetsTheWallOrPassesTheOpeningToTheRoomBehind) {
  // ingress: approach face at x = 3, opening 60 x 60 cm centred at (y 0, z 1.2), back wall of
  // the room 3 m behind.
  const Scene scene = build_scene(test::quiet(test::scenario("ingress")), 1);
  auto hit = scene.cast_ray(Vector3d(1.0, 0.0, 0.5), Vector3d(1, 0, 0), 10.0);
  ASSERT_TRUE(hit);
  EXPECT_NEAR(hit->distance_m, 2.0, 1e-12);
  ASSERT_GE(hit->box, 0);
  EXPECT_EQ(scene.boxes[hit->box].kind, Box::Kind::kWall);
  hit = scene.cast_ray(Vector3d(1.0, 0.0, 1.2), Vector3d(1, 0, 0), 10.0);
  ASSERT_TRUE(hit);
  EXPECT_NEAR(hit->distance_m, 5.0, 1e-12);
  EXPECT_EQ(scene.boxes[hit->box].kind, Box::Kind::kRoom);
  // Looking up inside the room: its ceiling at 2.5 m.
  hit = scene.cast_ray(Vector3d(4.5, 0.0, 1.0), Vector3d(0, 0, 1), 10.0);
  ASSERT_TRUE(hit);
  EXPECT_NEAR(hit->distance_m, 1.5, 1e-12);
  EXPECT_TRUE(hit->normal_W.isApprox(-Vector3d::UnitZ()));
}

}  // namespace
}  // namespace alight::sim
