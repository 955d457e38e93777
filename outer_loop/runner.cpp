#include "outer_loop/runner.hpp"

#include <algorithm>
#include <utility>

#include "common/msg_convert.hpp"
#include "outer_loop/convert.hpp"

namespace alight::outer_loop {

Runner::Runner(const OuterLoopParams& params, const PersistentState& restored, InputGate gate,
               RunnerOptions options)
    : controller_(params, restored), gate_(std::move(gate)), options_(std::move(options)) {}

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
  const AttitudeCommand cmd = controller_.update(setpoint_, pose_, now_utime);
  if (!controller_.started()) return std::nullopt;
  return cmd;
}

}  // namespace alight::outer_loop
