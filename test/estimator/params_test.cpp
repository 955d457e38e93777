// The estimator's parameters: defaults valid, errors name the full dotted key, the section loads.

#include "estimator/params.hpp"

#include <gtest/gtest.h>

#include "estimator/estimator.hpp"

namespace alight::estimator {
namespace {

std::string error_of(const std::string& yaml) {
  try {
    load_estimator_params(ParamNode::from_string(yaml, "v.yaml"));
  } catch (const ParamError& e) {
    return e.what();
  }
  return "";
}

TEST(EstimatorParamsTest, DefaultsAreValidAndAbsentSectionKeepsThem) {
  EXPECT_NO_THROW(EstimatorParams{}.validate());
  const EstimatorParams p = load_estimator_params(ParamNode::from_string("other: 1\n"));
  EXPECT_EQ(p.range.sigma_m, EstimatorParams{}.range.sigma_m);
}

TEST(EstimatorParamsTest, ReadsNestedKeys) {
  const EstimatorParams p = load_estimator_params(ParamNode::from_string(
      "estimator:\n  history_s: 0.8\n  range:\n    t_B_R_m: [0.1, 0, -0.04]\n"
      "  flow:\n    min_inliers: 20\n  init:\n    yaw_deg: 90\n"));
  EXPECT_EQ(p.history_s, 0.8);
  EXPECT_EQ(p.range.t_B_R_m, Vector3d(0.1, 0, -0.04));
  EXPECT_EQ(p.flow.min_inliers, 20);
  EXPECT_EQ(p.init.yaw_deg, 90);
}

TEST(EstimatorParamsTest, ErrorsNameTheFullKey) {
  EXPECT_NE(error_of("estimator:\n  range:\n    sigma_m: -1\n").find("estimator.range.sigma_m"),
            std::string::npos);
  EXPECT_NE(
      error_of("estimator:\n  range:\n    max_range_m: 0.05\n").find("estimator.range.max_range_m"),
      std::string::npos);
  EXPECT_NE(error_of("estimator:\n  health:\n    pos_sigma_lost_m: 0.5\n")
                .find("estimator.health.pos_sigma_lost_m"),
            std::string::npos);
  // The flow camera's mounting is cameras.downward's, not a key of its own.
  EXPECT_NE(error_of("estimator:\n  flow:\n    mount: forward\n").find("estimator.flow.mount"),
            std::string::npos);
  EXPECT_NE(error_of("estimator:\n  baro:\n    sigma: 1\n").find("sigma"), std::string::npos);
  EXPECT_NE(error_of("estimator:\n  max_ahead_s: 0.1\n").find("estimator.health.imu_lost_s"),
            std::string::npos);
}

TEST(EstimatorParamsTest, TheFlowCameraIsTheVehiclesDownwardCamera) {
  const EstimatorParams p = load_estimator_params(
      ParamNode::from_string("cameras:\n  downward:\n    camera_info: c.yaml\n    mount: downward\n"
                             "    rpy_offset_deg: [1, 0, 0]\n    t_B_C_m: [0.05, 0, -0.06]\n"));
  EXPECT_EQ(p.flow.t_B_C_m, Vector3d(0.05, 0, -0.06));
  EXPECT_FALSE(p.flow.R_BC().isApprox(R_BC_downward()));  // the 1 degree offset is applied
  EXPECT_TRUE(p.flow.R_BC().isApprox(R_BC_downward() * rotation_from_rpy(M_PI / 180, 0, 0)));
}

TEST(EstimatorParamsTest, TheEstimatorRefusesInvalidParameters) {
  EstimatorParams p;
  p.imu.accel_noise_density = -1;
  EXPECT_THROW(Estimator{p}, ParamError);
}

TEST(EstimatorParamsTest, EveryParameterHasAUnitOrAMeaning) {
  for (const auto& info : EstimatorParams::schema().params(EstimatorParams{})) {
    EXPECT_FALSE(info.doc.empty()) << info.key;
    EXPECT_TRUE(info.key.find('.') != std::string::npos || info.key == "gravity_mps2" ||
                info.key == "history_s" || info.key == "max_ahead_s" || info.key == "max_queued")
        << info.key;
  }
}

}  // namespace
}  // namespace alight::estimator
