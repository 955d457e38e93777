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
      "  flow:\n    mount: forward\n  init:\n    yaw_deg: 90\n"));
  EXPECT_EQ(p.history_s, 0.8);
  EXPECT_EQ(p.range.t_B_R_m, Vector3d(0.1, 0, -0.04));
  EXPECT_TRUE(p.flow.R_BC().isApprox(R_BC_forward()));
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
  EXPECT_NE(error_of("estimator:\n  flow:\n    mount: sideways\n").find("estimator.flow.mount"),
            std::string::npos);
  EXPECT_NE(error_of("estimator:\n  baro:\n    sigma: 1\n").find("sigma"), std::string::npos);
  EXPECT_NE(error_of("estimator:\n  max_ahead_s: 0.1\n").find("estimator.health.imu_lost_s"),
            std::string::npos);
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
