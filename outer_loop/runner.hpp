#pragma once
// What the alight-outer-loop node does with its inputs, without LCM or clocks (tested in
// test/outer_loop/runner_test.cpp): messages through the validating conversions and the stamp
// guard (both reported through an InputGate, which the node wires to Node::reject_value and
// Node::accept_stamp), the controller stepped at the newest accepted input stamp, and a timer
// tick that keeps the failsafe sequence running when every input has stopped.
//
// Beyond the boundary checks (issue: anyone on the network could steer or disarm the vehicle):
//  - a KILL setpoint stops the motors only with the operator's signed CMD_KILL attached
//    (position_setpoint_t.kill_authority, checked by authorise_kill); otherwise it is a plain
//    motors-off (a landing), and counted;
//  - poses pass an innovation gate (common/pose_gate.hpp): a pose that jumps from its prediction
//    is refused and counted, and a refusal streak of 0.1 s latches the gate, so the controller
//    sees the pose lost (hold level, then the blind descent), never re-centred on the new
//    stream.
// A second publisher on the setpoint or pose channel is refused by the node before any of this
// (common/bus_auth.hpp) and shown on the ground station; the loop goes on with the channel's own
// publisher. Landing on a contest would be worse: a vertical landing from wherever the vehicle
// happens to be comes down on the platform's edge as often as not, which a refused forgery
// never does.
//
// Controller time: the newest accepted input stamp, so a replayed log gives the same commands.
// When nothing arrives, tick() advances it from that stamp by the steady time elapsed since it
// arrived (PX4 runs its failsafes on its own clock in the same way), so with motion capture and
// setpoints both gone the vehicle still holds level, descends and disarms on the ground.

#include <alight/operator_cmd_t.hpp>
#include <alight/pose_t.hpp>
#include <alight/position_setpoint_t.hpp>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>

#include "common/channels.hpp"
#include "common/pose_buffer.hpp"
#include "common/pose_gate.hpp"
#include "outer_loop/position_controller.hpp"

namespace alight::outer_loop {

/// The node's input boundary: reject_value counts a message a conversion refused (returns
/// false); accept_stamp judges a stamp (true: use the message).
struct InputGate {
  std::function<bool(const std::string& channel, const std::string& why)> reject_value;
  std::function<bool(const std::string& channel, int64_t utime)> accept_stamp;
  /// "" when `cmd` is the operator's signed CMD_KILL for this vehicle, else why not (unset:
  /// nothing is ever authorised).
  std::function<std::string(const operator_cmd_t& cmd)> authorise_kill;
};

/// The pose innovation gate's parameters for a vehicle flown with `p` (also autonomy's gate).
PoseGateParams pose_gate_params(const OuterLoopParams& p);

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
  /// The operator's KILL behind the motors stopping, once authorised (ATTITUDE_CMD carries it).
  const std::optional<operator_cmd_t>& kill_authority() const { return kill_authority_; }
  /// KILL setpoints without a valid authority, flown as a motors-off instead; and the last why.
  uint64_t kills_refused() const { return kills_refused_; }
  const std::string& last_kill_refusal() const { return last_kill_refusal_; }
  const PoseGate& pose_gate() const { return pose_gate_; }
  /// Controller time of the last step [us].
  int64_t now_utime() const { return now_utime_; }

 private:
  void accepted(int64_t utime, int64_t steady_us);
  std::optional<AttitudeCommand> step(int64_t now_utime, int64_t steady_us);

  PositionController controller_;
  InputGate gate_;
  PoseGate pose_gate_;
  std::optional<operator_cmd_t> kill_authority_;
  uint64_t kills_refused_ = 0;
  std::string last_kill_refusal_;
  RunnerOptions options_;
  std::optional<PoseSample> pose_;
  std::optional<PositionSetpoint> setpoint_;
  int64_t newest_utime_ = 0;      // newest accepted input stamp
  int64_t newest_steady_us_ = 0;  // steady time it arrived
  std::optional<int64_t> last_step_steady_us_;
  int64_t now_utime_ = 0;
};

}  // namespace alight::outer_loop
