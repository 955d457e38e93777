#include "common/msg_convert.hpp"

#include <gtest/gtest.h>

namespace alight {
namespace {

TEST(MsgConvertTest, PoseRoundTrip) {
  PoseSample s;
  s.utime = 1234567;
  s.p_W_B = Vector3d(1, -2, 3);
  s.v_W_B = Vector3d(0.1, 0.2, -0.3);
  s.omega_B = Vector3d(0.01, -0.02, 0.5);
  s.q_WB = Quaterniond(Eigen::AngleAxisd(0.4, Vector3d(0.2, 0.3, 1).normalized()));
  const PoseSample back = from_msg(to_msg(s, 42));
  EXPECT_EQ(back.utime, s.utime);
  EXPECT_TRUE(back.p_W_B.isApprox(s.p_W_B));
  EXPECT_TRUE(back.v_W_B.isApprox(s.v_W_B));
  EXPECT_TRUE(back.omega_B.isApprox(s.omega_B));
  EXPECT_LT(back.q_WB.angularDistance(s.q_WB), 1e-12);
  EXPECT_EQ(to_msg(s, 42).seq, 42);
}

}  // namespace
}  // namespace alight
