#include "common/pose_gate.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace alight {

const char* pose_gate_verdict_name(PoseGateVerdict v) {
  switch (v) {
    case PoseGateVerdict::kAccepted:
      return "accepted";
    case PoseGateVerdict::kFirst:
      return "accepted (first)";
    case PoseGateVerdict::kPositionJump:
      return "position jumps from its prediction";
    case PoseGateVerdict::kAttitudeJump:
      return "attitude jumps from its prediction";
    case PoseGateVerdict::kLatched:
      return "poses disagreed for too long: refused until on the ground";
  }
  return "?";
}

void PoseGate::reset() {
  last_.reset();
  streak_since_.reset();
  latched_ = false;
}

PoseGateVerdict PoseGate::check(const PoseSample& pose) {
  const auto refuse = [&](PoseGateVerdict v, const std::string& why) {
    ++refused_;
    last_why_ = why;
    if (!streak_since_) streak_since_ = pose.utime;
    if (static_cast<double>(pose.utime - *streak_since_) * 1e-6 >= params_.sustained_s)
      latched_ = true;
    return v;
  };
  if (latched_)
    return refuse(PoseGateVerdict::kLatched, pose_gate_verdict_name(PoseGateVerdict::kLatched));
  if (!last_) {
    last_ = pose;
    return PoseGateVerdict::kFirst;
  }
  // A pose older than the reference is the stamp guard's business; judged as a gap of zero.
  const double dt = std::max(0.0, static_cast<double>(pose.utime - last_->utime) * 1e-6);
  const Vector3d predicted = last_->p_W_B + last_->v_W_B * dt;
  const double allowed_m = params_.tolerance_m + 0.5 * params_.max_accel_mps2 * dt * dt;
  const double off_m = (pose.p_W_B - predicted).norm();
  char why[160];
  if (!(off_m <= allowed_m)) {
    std::snprintf(why, sizeof why, "position %.3f m from its prediction (gate %.3f m after %.3f s)",
                  off_m, allowed_m, dt);
    return refuse(PoseGateVerdict::kPositionJump, why);
  }
  const double turned = last_->q_WB.angularDistance(pose.q_WB);
  const double allowed_rad = params_.tolerance_rad + params_.max_rate_radps * dt;
  if (!(turned <= allowed_rad)) {
    std::snprintf(why, sizeof why, "attitude turned %.3f rad (gate %.3f rad after %.3f s)", turned,
                  allowed_rad, dt);
    return refuse(PoseGateVerdict::kAttitudeJump, why);
  }
  last_ = pose;
  streak_since_.reset();
  return PoseGateVerdict::kAccepted;
}

}  // namespace alight
