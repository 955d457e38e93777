#include "common/params.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "common/camera_mount.hpp"
#include "common/pose_buffer.hpp"
#include "test/common/expect_param_error.hpp"

namespace alight {
namespace {

using test::expect_param_error;

struct Refinement {
  int n_min = 10;
  double eps_horz_m = 0.01;
  void validate() const {
    param_check(n_min >= 1, "n_min", n_min, "must be >= 1");
    param_check(eps_horz_m > 0, "eps_horz_m", eps_horz_m, "must be > 0");
  }
};

Refinement load(const std::string& yaml) {
  const auto root = ParamNode::from_string(yaml, "config/vehicles/test.yaml");
  const auto sec = root.child("autonomy").child("refinement");
  Refinement r;
  sec.read("n_min", r.n_min);
  sec.read("eps_horz_m", r.eps_horz_m);
  sec.finish();
  sec.validate(r);
  return r;
}

TEST(ParamsTest, AbsentKeysKeepTheirDefaults) {
  const auto r = load("autonomy:\n  refinement:\n    n_min: 12\n");
  EXPECT_EQ(r.n_min, 12);
  EXPECT_DOUBLE_EQ(r.eps_horz_m, 0.01);
}

TEST(ParamsTest, ValidationErrorNamesFileKeyAndValue) {
  const auto e = expect_param_error([] { load("autonomy:\n  refinement:\n    n_min: -3\n"); });
  EXPECT_EQ(e.file(), "config/vehicles/test.yaml");
  EXPECT_EQ(e.key(), "autonomy.refinement.n_min");
  EXPECT_EQ(e.value(), "-3");
  EXPECT_EQ(std::string(e.what()),
            "config/vehicles/test.yaml: autonomy.refinement.n_min = -3: must be >= 1");
}

TEST(ParamsTest, WrongTypeNamesTheExpectedType) {
  const auto e = expect_param_error([] { load("autonomy:\n  refinement:\n    n_min: ten\n"); });
  EXPECT_EQ(e.key(), "autonomy.refinement.n_min");
  EXPECT_EQ(e.value(), "ten");
  EXPECT_NE(std::string(e.what()).find("integer"), std::string::npos);
}

TEST(ParamsTest, MisspeltKeyIsRejected) {
  const auto e = expect_param_error([] { load("autonomy:\n  refinement:\n    n_mim: 4\n"); });
  EXPECT_EQ(e.key(), "autonomy.refinement.n_mim");
  EXPECT_NE(e.problem().find("unknown key"), std::string::npos);
}

TEST(ParamsTest, MissingSectionIsNamed) {
  const auto e = expect_param_error([] { load("autonomy: {}\n"); });
  EXPECT_EQ(e.key(), "autonomy.refinement");
  EXPECT_EQ(e.value(), "<missing>");
}

TEST(ParamsTest, SectionThatIsNotAMappingIsRejected) {
  const auto e = expect_param_error([] { load("autonomy:\n  refinement: 3\n"); });
  EXPECT_EQ(e.key(), "autonomy.refinement");
  EXPECT_EQ(e.value(), "3");
}

TEST(ParamsTest, InvalidYamlNamesTheLine) {
  const auto e = expect_param_error([] { ParamNode::from_string("a: 1\nb: [1, 2\n", "f.yaml"); });
  EXPECT_EQ(e.file(), "f.yaml");
  EXPECT_NE(std::string(e.what()).find("line"), std::string::npos);
}

TEST(ParamsTest, MissingFileIsNamed) {
  const auto e = expect_param_error([] { ParamNode::load_file("/nonexistent/alight.yaml"); });
  EXPECT_EQ(e.file(), "/nonexistent/alight.yaml");
  EXPECT_NE(e.problem().find("cannot open"), std::string::npos);
}

TEST(ParamsTest, VectorOfWrongLengthIsRejected) {
  const auto root = ParamNode::from_string("t: [1, 2]\n", "v.yaml");
  Vector3d t;
  const auto e = expect_param_error([&] { root.require("t", t); });
  EXPECT_EQ(e.key(), "t");
  EXPECT_EQ(e.value(), "[1, 2]");
}

TEST(ParamsTest, RequiredKeyMissingIsNamed) {
  const auto root = ParamNode::from_string("a: 1\n", "r.yaml");
  double b = 0;
  const auto e = expect_param_error([&] { root.require("b", b); });
  EXPECT_EQ(std::string(e.what()), "r.yaml: b = <missing>: required key is missing");
}

TEST(ParamsTest, ListOfMappingsNamesTheIndex) {
  const auto root = ParamNode::from_string("procs:\n  - {name: a}\n  - 7\n", "l.yaml");
  const auto e = expect_param_error([&] { root.child_list("procs"); });
  EXPECT_EQ(e.key(), "procs[1]");
}

TEST(ParamsTest, PoseBufferParamsValidate) {
  PoseBufferParams p;
  p.max_gap_s = -1;
  const auto e = expect_param_error([&] { p.validate(); });
  EXPECT_EQ(e.key(), "max_gap_s");
  EXPECT_EQ(e.value(), "-1");
}

TEST(ParamsTest, CameraMountResolvesRelativeToTheVehicleFile) {
  const std::string vehicle = std::string(ALIGHT_SOURCE_DIR) + "/config/vehicles/pelican.yaml";
  const auto root = ParamNode::load_file(vehicle);
  const auto down = load_camera_mount(root, "downward");
  EXPECT_TRUE(std::filesystem::exists(down.camera_info_path)) << down.camera_info_path;
  EXPECT_TRUE(is_rotation(down.R_BC));
  EXPECT_TRUE(down.R_BC.isApprox(R_BC_downward()));
  const auto fwd = load_camera_mount(root, "forward");
  EXPECT_TRUE(fwd.R_BC.isApprox(R_BC_forward()));
}

TEST(ParamsTest, CameraMountRejectsUnknownMount) {
  const auto root = ParamNode::from_string(
      "cameras:\n  downward:\n    camera_info: x.yaml\n    mount: sideways\n    t_B_C_m: [0,0,0]\n",
      "veh.yaml");
  const auto e = expect_param_error([&] { load_camera_mount(root, "downward"); });
  EXPECT_EQ(e.key(), "cameras.downward.mount");
  EXPECT_EQ(e.value(), "sideways");
}

// Regression (issue 14): `.inf` loaded for pose_lost_s / failsafe_disarm_after_s /
// setpoint_lost_s and turned the failsafes off; NaN passed every `x > 0` check as false but
// `!(x <= 0)` style checks as true.
TEST(ParamsTest, NonFiniteNumbersAreRefusedWithTheFullKey) {
  for (const char* v : {".inf", "-.inf", ".nan", ".NaN", "1e999"}) {
    const auto e = expect_param_error(
        [&] { load(std::string("autonomy:\n  refinement:\n    eps_horz_m: ") + v + "\n"); });
    EXPECT_EQ(e.key(), "autonomy.refinement.eps_horz_m") << v;
    EXPECT_EQ(e.value(), v);
    EXPECT_EQ(e.file(), "config/vehicles/test.yaml");
    EXPECT_NE(std::string(e.what()).find("finite"), std::string::npos) << e.what();
  }
}

TEST(ParamsTest, NonFiniteNumbersInAListAreRefused) {
  const auto root = ParamNode::from_string("p: [1, .nan, 3]\n", "f.yaml");
  Eigen::Vector3d v;
  const auto e = expect_param_error([&] { root.read("p", v); });
  EXPECT_EQ(e.key(), "p");
}

// Regression (issue 14): a duplicate YAML key was taken silently (yaml-cpp keeps both entries
// and lookups see the first, so the later line, usually the edit, did nothing).
TEST(ParamsTest, DuplicateKeyIsRefusedWithItsFullKeyAndLine) {
  const auto e = expect_param_error(
      [] { load("autonomy:\n  refinement:\n    n_min: 3\n    eps_horz_m: 0.1\n    n_min: 5\n"); });
  EXPECT_EQ(e.key(), "autonomy.refinement.n_min");
  EXPECT_EQ(e.value(), "5");
  EXPECT_EQ(e.file(), "config/vehicles/test.yaml");
  EXPECT_NE(std::string(e.what()).find("line 5"), std::string::npos) << e.what();
}

TEST(ParamsTest, DuplicateKeyInsideAListIsRefused) {
  const auto e = expect_param_error(
      [] { ParamNode::from_string("procs:\n  - name: a\n    name: b\n", "launch.yaml"); });
  EXPECT_EQ(e.key(), "procs[0].name");
}

TEST(ParamsTest, SameKeyInDifferentMappingsIsFine) {
  EXPECT_NO_THROW(ParamNode::from_string("a:\n  x: 1\nb:\n  x: 2\n", "f.yaml"));
}

// Regression (issue 14, found by fuzzing): a key that is a list or a mapping threw yaml-cpp's
// BadConversion from finish(), and every node exited 1 naming no key.
TEST(ParamsTest, NonScalarKeyIsAParamErrorNamingWhere) {
  const auto root = ParamNode::from_string("ground_station:\n  {[a]: 1}\n", "station.yaml");
  const auto sec = root.child("ground_station");
  const auto e = expect_param_error([&] { sec.finish(); });
  EXPECT_EQ(e.file(), "station.yaml");
  EXPECT_EQ(e.key(), "ground_station.<list as a key>");
}

}  // namespace
}  // namespace alight
