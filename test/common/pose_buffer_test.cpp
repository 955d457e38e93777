#include "common/pose_buffer.hpp"

#include <gtest/gtest.h>

namespace alight {
namespace {

// Analytic trajectory: constant velocity along a line, constant yaw rate about z.
PoseSample truth(int64_t utime) {
  const double t = 1e-6 * static_cast<double>(utime - 1'000'000'000'000);
  PoseSample s;
  s.utime = utime;
  s.v_W_B = Vector3d(0.5, -0.2, 0.1);
  s.p_W_B = Vector3d(1, 2, 3) + t * s.v_W_B;
  s.omega_B = Vector3d(0, 0, 0.8);
  s.q_WB = Quaterniond(Eigen::AngleAxisd(0.3 + 0.8 * t, Vector3d::UnitZ()));
  return s;
}

constexpr int64_t kBufferT0 = 1'000'000'000'000;

PoseBuffer filled(const PoseBufferParams& p, int n = 100, int64_t step_us = 10'000) {
  PoseBuffer buf(p);
  for (int i = 0; i < n; ++i) buf.add(truth(kBufferT0 + i * step_us));
  return buf;
}

TEST(PoseBufferTest, InterpolatesAnAnalyticTrajectoryExactly) {
  const PoseBuffer buf = filled({});
  for (int64_t dt = 0; dt <= 990'000; dt += 3'337) {
    const auto s = buf.at(kBufferT0 + dt);
    ASSERT_TRUE(s.has_value()) << dt;
    const PoseSample t = truth(kBufferT0 + dt);
    EXPECT_LT((s->p_W_B - t.p_W_B).norm(), 1e-9);
    EXPECT_LT(s->q_WB.angularDistance(t.q_WB), 1e-9);  // slerp is exact for a constant rate
    EXPECT_EQ(s->utime, kBufferT0 + dt);
  }
}

TEST(PoseBufferTest, RefusesExtrapolationBeyondTheConfiguredGap) {
  PoseBufferParams p;
  p.max_extrapolation_s = 0.02;
  const PoseBuffer buf = filled(p);
  const int64_t newest = buf.newest_utime();
  PoseSample s;
  EXPECT_EQ(buf.lookup(newest + 19'000, &s), PoseBuffer::Status::kOk);
  EXPECT_LT((s.p_W_B - truth(newest + 19'000).p_W_B).norm(), 1e-9);
  EXPECT_LT(s.q_WB.angularDistance(truth(newest + 19'000).q_WB), 1e-9);
  EXPECT_EQ(buf.lookup(newest + 21'000, &s), PoseBuffer::Status::kAfterNewest);
  EXPECT_EQ(buf.lookup(kBufferT0 - 1, &s), PoseBuffer::Status::kBeforeHistory);
}

TEST(PoseBufferTest, DefaultNeverExtrapolates) {
  const PoseBuffer buf = filled({});
  EXPECT_FALSE(buf.at(buf.newest_utime() + 1).has_value());
  EXPECT_TRUE(buf.at(buf.newest_utime()).has_value());
}

TEST(PoseBufferTest, RefusesToInterpolateAcrossADropout) {
  PoseBufferParams p;
  p.max_gap_s = 0.05;
  PoseBuffer buf(p);
  buf.add(truth(kBufferT0));
  buf.add(truth(kBufferT0 + 10'000));
  buf.add(truth(kBufferT0 + 200'000));  // 190 ms of missing mocap
  PoseSample s;
  EXPECT_EQ(buf.lookup(kBufferT0 + 100'000, &s), PoseBuffer::Status::kGap);
  EXPECT_EQ(buf.lookup(kBufferT0 + 5'000, &s), PoseBuffer::Status::kOk);
}

TEST(PoseBufferTest, EmptyBufferSaysSo) {
  PoseBuffer buf;
  PoseSample s;
  EXPECT_EQ(buf.lookup(kBufferT0, &s), PoseBuffer::Status::kEmpty);
}

TEST(PoseBufferTest, OutOfOrderSamplesAreInsertedInOrder) {
  PoseBuffer buf;
  buf.add(truth(kBufferT0 + 20'000));
  buf.add(truth(kBufferT0));
  buf.add(truth(kBufferT0 + 10'000));
  EXPECT_EQ(buf.size(), 3u);
  EXPECT_EQ(buf.oldest_utime(), kBufferT0);
  const auto s = buf.at(kBufferT0 + 15'000);
  ASSERT_TRUE(s);
  EXPECT_LT((s->p_W_B - truth(kBufferT0 + 15'000).p_W_B).norm(), 1e-9);
}

TEST(PoseBufferTest, HistoryIsTrimmed) {
  PoseBufferParams p;
  p.history_s = 0.1;
  const PoseBuffer buf = filled(p, 100, 10'000);
  EXPECT_LE(buf.size(), 11u);
  EXPECT_GE(buf.oldest_utime(), buf.newest_utime() - 100'000);
}

TEST(PoseBufferTest, SampleOlderThanHistoryIsIgnored) {
  PoseBufferParams p;
  p.history_s = 0.1;
  PoseBuffer buf = filled(p, 100, 10'000);
  EXPECT_FALSE(buf.add(truth(kBufferT0)));
}

// Regression (issue 14, found by fuzzing): a pose stamped near INT64_MIN made the history
// window's start overflow; the buffer emptied itself and read front() of an empty deque.
TEST(PoseBufferRegression, ExtremeStampsNeverEmptyTheBuffer) {
  PoseBuffer buf = filled(PoseBufferParams{});
  PoseSample s = truth(kBufferT0);
  s.utime = INT64_MIN + 5;
  EXPECT_FALSE(buf.add(s));
  PoseBuffer fresh;
  EXPECT_TRUE(fresh.add(s));
  s.utime = INT64_MIN;
  EXPECT_TRUE(fresh.add(s));
  PoseSample out;
  EXPECT_EQ(fresh.lookup(INT64_MIN, &out), PoseBuffer::Status::kOk);
}

}  // namespace
}  // namespace alight
