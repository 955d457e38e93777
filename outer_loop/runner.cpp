#include "outer_loop/runner.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include "common/msg_convert.hpp"
#include "outer_loop/convert.hpp"

namespace alight::outer_loop {

PoseGateParams pose_gate_params(const OuterLoopParams& p) {
  // Twice what the loop can command (the tilt limit's horizontal and the vertical limit), the
  // other half for what it does not command (gusts, contact).
  PoseGateParams g;
  const double commanded =
      std::hypot(p.gravity_mps2 * std::tan(p.max_tilt_deg * M_PI / 180.0), p.max_accel_z_mps2);
  g.max_accel_mps2 = 2.0 * commanded;
  return g;
}

Runner::Runner(const OuterLoopParams& params, const PersistentState& restored, InputGate gate,
               RunnerOptions options)
    : controller_(params, restored),
      gate_(std::move(gate)),
      pose_gate_(pose_gate_params(params)),
      options_(std::move(options)) {}

void Runner::accepted(int64_t utime, int64_t steady_us) {
  if (utime > newest_utime_) {
    newest_utime_ = utime;
    newest_steady_us_ = steady_us;
  }
}

std::optional<AttitudeCommand> Runner::on_pose(const pose_t& msg, int64_t steady_us) {
  std::string why;
  // Values before the stamp: a refused message must not move the stamp guard.
  auto pose = pose_from_msg(msg, &why);
  if (!pose) {
    gate_.reject_value(options_.pose_channel, why);
    return std::nullopt;
  }
  if (!gate_.accept_stamp(options_.pose_channel, msg.utime)) return std::nullopt;
  if (!pose_gate_ok(pose_gate_.check(*pose))) {
    gate_.reject_value(options_.pose_channel, "innovation gate: " + pose_gate_.last_why());
    return std::nullopt;
  }
  pose_ = *pose;
  accepted(msg.utime, steady_us);
  return step(newest_utime_, steady_us);
}

std::optional<AttitudeCommand> Runner::on_setpoint(const position_setpoint_t& msg,
                                                   int64_t steady_us) {
  std::string why;
  auto sp = setpoint_from_msg(msg, &why);
  if (!sp) {
    gate_.reject_value(options_.setpoint_channel, why);
    return std::nullopt;
  }
  if (!gate_.accept_stamp(options_.setpoint_channel, msg.utime)) return std::nullopt;
  if (sp->kill) {
    const std::string why =
        gate_.authorise_kill ? gate_.authorise_kill(msg.kill_authority) : "no operator key";
    if (why.empty()) {
      kill_authority_ = msg.kill_authority;
    } else {
      // Not the operator's: a motors-off, which the controller honours on the ground only.
      sp->kill = false;
      ++kills_refused_;
      last_kill_refusal_ = why;
    }
  }
  setpoint_ = *sp;
  accepted(msg.utime, steady_us);
  return step(newest_utime_, steady_us);
}

std::optional<AttitudeCommand> Runner::tick(int64_t steady_us) {
  if (newest_utime_ == 0 || !last_step_steady_us_) return std::nullopt;
  const int64_t quiet_us = static_cast<int64_t>(options_.tick_quiet_s * 1e6);
  if (steady_us - *last_step_steady_us_ < quiet_us) return std::nullopt;
  return step(newest_utime_ + std::max<int64_t>(0, steady_us - newest_steady_us_), steady_us);
}

std::optional<AttitudeCommand> Runner::step(int64_t now_utime, int64_t steady_us) {
  now_utime_ = now_utime;
  last_step_steady_us_ = steady_us;
  AttitudeCommand cmd = controller_.update(setpoint_, pose_, now_utime);
  if (pose_gate_.latched() && cmd.mode == Mode::kHoldLevel)
    cmd.reason = "pose disagrees with its prediction (innovation gate): level, hover thrust";
  if (pose_gate_.latched() && cmd.mode == Mode::kFailsafeDescent)
    cmd.reason = "pose disagrees with its prediction (innovation gate): open-loop slow descent";
  // On the ground and disarmed the next flight starts with a fresh gate.
  if (!cmd.armed && pose_gate_.latched()) pose_gate_.reset();
  if (!controller_.started()) return std::nullopt;
  return cmd;
}

}  // namespace alight::outer_loop
