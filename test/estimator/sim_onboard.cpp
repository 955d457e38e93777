#include "sim_onboard.hpp"

#include <time.h>

#include <algorithm>

#include "common/camera_mount.hpp"
#include "common/image_msg.hpp"
#include "common/msg_convert.hpp"
#include "common/params.hpp"
#include "estimator/convert.hpp"
#include "estimator/params.hpp"
#include "sim/sim_msgs.hpp"

namespace alight::estimator::test {

SimOnboard::SimOnboard(const std::string& vehicle_file, bool measure_cpu)
    : measure_cpu_(measure_cpu) {
  // As estimator_node.cpp builds it.
  const ParamNode root = ParamNode::load_file(vehicle_file);
  const EstimatorParams params = load_estimator_params(root);
  const CameraMount mount = load_camera_mount(root, "downward");
  onboard_ = std::make_unique<Onboard>(params, load_camera_info(mount.camera_info_path));
  if (measure_cpu_) {
    // The thread CPU clock is a system call: its own cost is of the order of an IMU sample's.
    constexpr int kN = 2000;
    const int64_t t0 = cpu_ns();
    for (int k = 0; k < kN; ++k) cpu_ns();
    clock_overhead_ns_ = (cpu_ns() - t0) / (kN + 1);
  }
}

int64_t SimOnboard::cpu_ns() const {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return int64_t(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

namespace {
// Adds one call's time to a tally.
void tally(int64_t dt_ns, int64_t* sum, int64_t* n, int64_t* max = nullptr) {
  dt_ns = std::max<int64_t>(dt_ns, 0);
  *sum += dt_ns;
  ++*n;
  if (max) *max = std::max(*max, dt_ns);
}
}  // namespace

std::optional<Published> SimOnboard::add_imu(const sim::ImuSample& s) {
  const ImuSample imu = from_msg(sim::to_msg(s));
  const int64_t t0 = measure_cpu_ ? cpu_ns() : 0;
  const Outcome o = onboard_->add_imu(imu);
  std::optional<Published> out;
  if (o == Outcome::kFused) {
    const State st = onboard_->state();
    if (st.initialised) {
      Published p;
      p.estimate = to_msg(st, imu.gyro_B, seq_);
      p.pose_msg = to_pose_msg(st, imu.gyro_B, seq_);
      ++seq_;
      if (const auto pose = pose_from_msg(p.pose_msg, nullptr)) {
        p.pose = *pose;
        out = std::move(p);
      }
    }
  }
  if (measure_cpu_)
    tally(cpu_ns() - t0 - clock_overhead_ns_, &cost_.imu_ns, &cost_.n_imu, &cost_.max_imu_ns);
  return out;
}

void SimOnboard::add_range(const sim::RangeSample& s) {
  const RangeSample r = from_msg(sim::to_msg(s));
  const int64_t t0 = measure_cpu_ ? cpu_ns() : 0;
  onboard_->add_range(r);
  if (measure_cpu_) tally(cpu_ns() - t0 - clock_overhead_ns_, &cost_.range_ns, &cost_.n_range);
}

void SimOnboard::add_baro(const sim::BaroSample& s) {
  const BaroSample b = from_msg(sim::to_msg(s));
  const int64_t t0 = measure_cpu_ ? cpu_ns() : 0;
  onboard_->add_baro(b);
  if (measure_cpu_) tally(cpu_ns() - t0 - clock_overhead_ns_, &cost_.baro_ns, &cost_.n_baro);
}

void SimOnboard::add_frame(const sim::CameraFrame& f) {
  // image_from_msg of the simulator's mono8 image_t gives these pixels.
  const int64_t t0 = measure_cpu_ ? cpu_ns() : 0;
  onboard_->add_frame(f.pixels, f.utime);
  if (measure_cpu_) {
    const int64_t dt_ns = cpu_ns() - t0 - clock_overhead_ns_;
    tally(dt_ns, &cost_.frame_ns, &cost_.n_frames, &cost_.max_frame_ns);
    cost_.frame_us.push_back(static_cast<int32_t>(std::max<int64_t>(dt_ns, 0) / 1000));
  }
}

}  // namespace alight::estimator::test
