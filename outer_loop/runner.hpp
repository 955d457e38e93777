#pragma once
// What the alight-outer-loop node does with its inputs, without LCM or clocks (tested in
// test/outer_loop/runner_test.cpp): messages through the validating conversions and the stamp
// guard (both reported through an InputGate, which the node wires to Node::reject_value and
// Node::accept_stamp), the controller stepped at the newest accepted input stamp, and a timer
// tick that keeps the failsafe sequence running when every input has stopped.
//
// Controller time: the newest accepted input stamp, so a replayed log gives the same commands.
// When nothing arrives, tick() advances it from that stamp by the steady time elapsed since it
// arrived (PX4 runs its failsafes on its own clock in the same way), so with motion capture and
// setpoints both gone the vehicle still holds level, descends and disarms on the ground.

#include <alight/pose_t.hpp>
#include <alight/position_setpoint_t.hpp>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>

#include "common/channels.hpp"
#include "common/pose_buffer.hpp"
#include "outer_loop/position_controller.hpp"

namespace alight::outer_loop {

/// The node's input boundary: reject_value counts a message a conversion refused (returns
/// false); accept_stamp judges a stamp (true: use the message).
struct InputGate {
  std::function<bool(const std::string& channel, const std::string& why)> reject_value;
  std::function<bool(const std::string& channel, int64_t utime)> accept_stamp;
};

struct RunnerOptions {
  std::string pose_channel = channels::kMocapPose;
  std::string setpoint_channel = channels::kPositionSetpoint;
  /// tick() steps the controller only when no input stepped it for this long [s] (steady).
  double tick_quiet_s = 0.02;
};

class Runner {
 public:
  Runner(const OuterLoopParams& params, const PersistentState& restored, InputGate gate,
         RunnerOptions options = {});

  /// A pose received at `steady_us`. Returns the command to publish: none when the message was
  /// refused, or while the controller has not started (no fresh pose and setpoint together yet).
  std::optional<AttitudeCommand> on_pose(const pose_t& msg, int64_t steady_us);
  std::optional<AttitudeCommand> on_setpoint(const position_setpoint_t& msg, int64_t steady_us);
  /// The node's timer (steady clock).
  std::optional<AttitudeCommand> tick(int64_t steady_us);

  const PositionController& controller() const { return controller_; }
  /// Controller time of the last step [us].
  int64_t now_utime() const { return now_utime_; }

 private:
  void accepted(int64_t utime, int64_t steady_us);
  std::optional<AttitudeCommand> step(int64_t now_utime, int64_t steady_us);

  PositionController controller_;
  InputGate gate_;
  RunnerOptions options_;
  std::optional<PoseSample> pose_;
  std::optional<PositionSetpoint> setpoint_;
  int64_t newest_utime_ = 0;      // newest accepted input stamp
  int64_t newest_steady_us_ = 0;  // steady time it arrived
  std::optional<int64_t> last_step_steady_us_;
  int64_t now_utime_ = 0;
};

}  // namespace alight::outer_loop
