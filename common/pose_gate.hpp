#pragma once
// Innovation gate on a pose stream (as EKF2 gates external vision, EKF2_EVP_GATE): a pose that
// lands further from where the last accepted one predicts (constant velocity) than its noise and
// the vehicle's largest acceleration allow is refused and counted. A forged pose shifted 30 cm
// is many times over the gate; a genuine stream after an occlusion is not (the allowance grows
// with the gap). The gate never re-centres on a refused stream: a refusal streak longer than
// `sustained_s` is a sustained disagreement, latched until reset() (the vehicle is on the
// ground), and the caller treats the pose as lost (hold, then descend). Pure.

#include <cstdint>
#include <optional>
#include <string>

#include "common/pose_buffer.hpp"

namespace alight {

struct PoseGateParams {
  /// Position noise the gate always allows [m]: motion capture's is about 1 mm and the onboard
  /// estimate's a few cm; a pose shifted by less than this cannot move a landing off a platform.
  double tolerance_m = 0.05;
  /// Attitude noise always allowed [rad].
  double tolerance_rad = 0.1;
  /// Largest acceleration the vehicle can have [m/s^2] (the caller derives it from its limits);
  /// the gate widens by half of it times the gap squared.
  double max_accel_mps2 = 10.0;
  /// Largest rotation rate [rad/s]: no attitude loop of these vehicles turns faster.
  double max_rate_radps = 6.0;
  /// A refusal streak this long is a sustained disagreement [s]: a single outlier (a marker
  /// swap) is shorter, and a shifted stream is latched before the widening allowance (above)
  /// could take it for the vehicle's own motion.
  double sustained_s = 0.1;
};

enum class PoseGateVerdict { kAccepted, kFirst, kPositionJump, kAttitudeJump, kLatched };
const char* pose_gate_verdict_name(PoseGateVerdict v);
inline bool pose_gate_ok(PoseGateVerdict v) {
  return v == PoseGateVerdict::kAccepted || v == PoseGateVerdict::kFirst;
}

class PoseGate {
 public:
  explicit PoseGate(PoseGateParams params = {}) : params_(params) {}

  /// Judges `pose` (stamped in its utime). Only an accepted pose becomes the reference.
  PoseGateVerdict check(const PoseSample& pose);
  /// True once refusals lasted sustained_s: every later pose is refused (kLatched).
  bool latched() const { return latched_; }
  /// Forgets the reference and the latch (on the ground, disarmed).
  void reset();
  uint64_t refused() const { return refused_; }
  /// What the last refusal was, for logs ("" when none).
  const std::string& last_why() const { return last_why_; }

 private:
  PoseGateParams params_;
  std::optional<PoseSample> last_;
  std::optional<int64_t> streak_since_;  // utime of the first refusal of the current streak
  bool latched_ = false;
  uint64_t refused_ = 0;
  std::string last_why_;
};

}  // namespace alight
