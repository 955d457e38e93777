#include "common/site.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "common/build_paths.hpp"
#include "test/common/expect_param_error.hpp"

namespace alight {
namespace {

using test::expect_param_error;

class SiteFileTest : public ::testing::Test {
 protected:
  std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("alight_site_test_" + std::to_string(::getpid()));
  void SetUp() override { std::filesystem::create_directories(dir); }
  void TearDown() override { std::filesystem::remove_all(dir); }
  std::string write(const std::string& text) const {
    const std::string p = (dir / "site.yaml").string();
    std::ofstream(p) << text;
    return p;
  }
};

TEST_F(SiteFileTest, ReadsTheAreaSection) {
  const SiteArea s =
      load_site(write("area: {size_m: [8, 5], center_xy_m: [1, -0.5], height_m: 3}\n"));
  EXPECT_EQ(s.min_xy_m(), Vector2d(-3.0, -3.0));
  EXPECT_EQ(s.max_xy_m(), Vector2d(5.0, 2.0));
  EXPECT_EQ(s.height_m, 3.0);
}

TEST_F(SiteFileTest, AScenarioIsASiteFileAndTheShippedSiteIsTheLandingRoom) {
  const std::string root = build::source_dir();
  const SiteArea scenario = load_site(root + "/config/scenarios/landing_moving_cart.yaml");
  const SiteArea shipped = load_site(root + "/config/sites/mocap_room.yaml");
  EXPECT_EQ(scenario.size_m, shipped.size_m);
  EXPECT_EQ(scenario.center_xy_m, shipped.center_xy_m);
  EXPECT_EQ(scenario.height_m, shipped.height_m);
}

TEST_F(SiteFileTest, ErrorsNameTheFileTheKeyAndTheValue) {
  const std::string f = write("area: {size_m: [6, -1], center_xy_m: [0, 0], height_m: 4}\n");
  const ParamError e = expect_param_error([&] { load_site(f); });
  EXPECT_EQ(e.file(), f);
  EXPECT_EQ(e.key(), "area.size_m");
  EXPECT_NE(e.value().find("-1"), std::string::npos) << e.value();

  const ParamError missing = expect_param_error(
      [&] { load_site(write("area: {size_m: [6, 6], center_xy_m: [0, 0]}\n")); });
  EXPECT_EQ(missing.key(), "area.height_m");
  const ParamError no_area = expect_param_error([&] { load_site(write("room: {}\n")); });
  EXPECT_EQ(no_area.key(), "area");
  const ParamError bad = expect_param_error(
      [&] { load_site(write("area: {size_m: [6, .nan], center_xy_m: [0, 0], height_m: 4}\n")); });
  EXPECT_EQ(bad.key(), "area.size_m");
}

TEST(NarrowToSite, NarrowsTheWallsAndTheCeilingNeverWidensAndKeepsTheFloor) {
  SiteArea room;  // 6 x 6 m around the origin, 4 m high
  Vector3d lo(-2.8, -4.0, -0.5), hi(4.5, 2.0, 2.3);
  ASSERT_TRUE(narrow_to_site(room, 0.2, 0.5, lo, hi));
  EXPECT_TRUE(lo.isApprox(Vector3d(-2.8, -2.8, -0.5)));  // the floor's z stays the vehicle's
  EXPECT_TRUE(hi.isApprox(Vector3d(2.8, 2.0, 2.3)));     // the ceiling 3.8 is above 2.3

  room.height_m = 2.0;
  ASSERT_TRUE(narrow_to_site(room, 0.2, 0.5, lo, hi));
  EXPECT_DOUBLE_EQ(hi.z(), 1.8);
}

TEST(NarrowToSite, ASiteBesideTheFenceLeavesItAsItWas) {
  SiteArea far;
  far.center_xy_m = Vector2d(10.0, 0.0);  // x 7 .. 13
  Vector3d lo(-3, -3, 0), hi(3, 3, 2.5);
  EXPECT_FALSE(narrow_to_site(far, 0.2, 0.5, lo, hi));
  EXPECT_EQ(lo, Vector3d(-3, -3, 0));
  EXPECT_EQ(hi, Vector3d(3, 3, 2.5));
  SiteArea edge;
  edge.center_xy_m = Vector2d(5.6, 0.0);  // x 2.6 .. 8.6: 0.4 m of the fence, 0.2 inside it
  EXPECT_FALSE(narrow_to_site(edge, 0.2, 0.5, lo, hi));
  EXPECT_TRUE(narrow_to_site(edge, 0.0, 0.3, lo, hi));
  EXPECT_DOUBLE_EQ(lo.x(), 2.6);
}

TEST(SiteText, NamesTheSiteAndTheFenceInForce) {
  SiteArea room;
  room.center_xy_m = Vector2d(1.5, 0.0);
  EXPECT_EQ(site_text(room), "size_m [6, 6] around [1.5, 0], height_m 4");
  EXPECT_EQ(fence_text(Vector3d(-2.8, -2.8, 0), Vector3d(2.8, 2.8, 2.3), ""),
            "[-2.80 -2.80 0.00] .. [2.80 2.80 2.30] m");
  EXPECT_EQ(fence_text(Vector3d::Zero(), Vector3d::Ones(), "room.yaml"),
            "[0.00 0.00 0.00] .. [1.00 1.00 1.00] m (the site room.yaml)");
}

}  // namespace
}  // namespace alight
