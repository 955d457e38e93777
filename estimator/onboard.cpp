#include "estimator/onboard.hpp"

#include <Eigen/Geometry>
#include <algorithm>

namespace alight::estimator {
namespace {

constexpr int64_t kImuKeepUs = 2'000'000;  // longer than any frame's wait for the IMU
constexpr size_t kMaxQueuedFrames = 8;

Matrix3d exp_so3(const Vector3d& theta) {
  const double angle = theta.norm();
  if (angle < 1e-12) return Matrix3d::Identity();
  return Eigen::AngleAxisd(angle, theta / angle).toRotationMatrix();
}

}  // namespace

Onboard::Onboard(const EstimatorParams& params, const CameraModel& camera)
    : params_(params),
      filter_(params),
      flow_(params.flow.front, camera),
      R_BC_(params.flow.R_BC()) {}

Outcome Onboard::add_imu(const ImuSample& imu) {
  const Outcome out = filter_.add_imu(imu);
  // Only what the filter took (alignment included) goes into the gyro history: a refused
  // sample (non-finite, absurd, out of order) never reaches the rotation between frames.
  if (out != Outcome::kFused) return out;
  imu_.push_back(imu);
  while (imu_.size() > 2 && imu_.back().utime - imu_.front().utime > kImuKeepUs) imu_.pop_front();
  drain();
  return out;
}

int Onboard::drain() {
  // In arrival order: a frame waits for the IMU, and the frames after it wait behind it.
  int n = 0;
  while (!frames_.empty() && !imu_.empty() && frames_.front().utime <= imu_.back().utime) {
    last_ = process(frames_.front());
    frames_.pop_front();
    ++n;
  }
  return n;
}

std::optional<Matrix3d> Onboard::body_rotation(int64_t t1_utime, int64_t t2_utime,
                                               const Vector3d& gyro_bias_B) const {
  if (t2_utime < t1_utime || imu_.size() < 2) return std::nullopt;
  if (t1_utime < imu_.front().utime || t2_utime > imu_.back().utime) return std::nullopt;
  Matrix3d R_B1B = Matrix3d::Identity();
  for (size_t k = 1; k < imu_.size(); ++k) {
    // Sample k is the mean rate over (utime[k-1], utime[k]].
    const int64_t a = std::max(imu_[k - 1].utime, t1_utime);
    const int64_t b = std::min(imu_[k].utime, t2_utime);
    if (b <= a) continue;
    R_B1B = R_B1B * exp_so3((imu_[k].gyro_B - gyro_bias_B) * 1e-6 * double(b - a));
  }
  return R_B1B;
}

FrameOutcome Onboard::add_frame(const cv::Mat& gray, int64_t utime) {
  FrameOutcome out;
  if (frames_.size() >= kMaxQueuedFrames) {
    frames_.pop_front();
    ++frames_dropped_;
    out.dropped = true;
  }
  frames_.push_back({gray, utime});
  out.processed = drain();
  out.flow = last_.flow;
  out.fused = last_.fused;
  out.queued = out.processed == 0;
  return out;
}

FrameOutcome Onboard::process(const Frame& f) {
  FrameOutcome out;
  const State s = filter_.state();
  if (!s.initialised) {
    flow_.reset();
    prev_frame_utime_.reset();
    out.flow = FlowReason::kNoPrevious;
    return out;
  }
  // R_WB at a past time t: the newest attitude rotated back by the gyro since t.
  const Matrix3d R_WB_now = s.q_WB.toRotationMatrix();
  const auto R_WB_at = [&](int64_t t) -> std::optional<Matrix3d> {
    const auto R_BtBnow = body_rotation(t, imu_.back().utime, s.gyro_bias_B);
    if (!R_BtBnow) return std::nullopt;
    return Matrix3d(R_WB_now * R_BtBnow->transpose());
  };
  Matrix3d R_C2C1 = Matrix3d::Identity();
  Vector3d n_C1 = R_BC_.transpose() * (R_WB_now.transpose() * Vector3d::UnitZ());
  std::optional<Matrix3d> R_B1B2, R_WB1;
  if (prev_frame_utime_) {
    R_B1B2 = body_rotation(*prev_frame_utime_, f.utime, s.gyro_bias_B);
    R_WB1 = R_WB_at(*prev_frame_utime_);
  }
  if (R_B1B2 && R_WB1) {
    R_C2C1 = R_BC_.transpose() * R_B1B2->transpose() * R_BC_;
    n_C1 = R_BC_.transpose() * (R_WB1->transpose() * Vector3d::UnitZ());
  } else {
    flow_.reset();  // the gyro does not cover the pair: start anew from this frame
  }
  const FlowResult r = flow_.add_frame(f.gray, f.utime, R_C2C1, n_C1);
  out.flow = r.reason;
  if (r.reason != FlowReason::kBadImage && r.reason != FlowReason::kBadTime)
    prev_frame_utime_ = f.utime;
  if (r.sample) out.fused = filter_.add_flow(*r.sample);
  out.sample = r.sample;
  return out;
}

}  // namespace alight::estimator
