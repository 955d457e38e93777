#pragma once
// Recent motion-capture history, queried at an image's exposure time (docs/ARCHITECTURE.md
// "Time"): vision needs R_V1, P_V1 at the reference image and R_V2 at the current one
// (paper eqs. 3 and 6), which fall between mocap samples.

#include <cstdint>
#include <deque>
#include <optional>

#include "common/geometry.hpp"

namespace alight {

template <class P>
class ParamSchema;

/// One motion-capture sample (domain form of alight::pose_t).
struct PoseSample {
  int64_t utime = 0;                           ///< sample time [us]
  Vector3d p_W_B = Vector3d::Zero();           ///< body origin in world [m]
  Quaterniond q_WB = Quaterniond::Identity();  ///< body to world
  Vector3d v_W_B = Vector3d::Zero();           ///< velocity in world [m/s]
  Vector3d omega_B = Vector3d::Zero();         ///< angular rate in body [rad/s]

  Isometry3d X_WB() const { return make_transform(q_WB.toRotationMatrix(), p_W_B); }
};

struct PoseBufferParams {
  double history_s = 5.0;
  double max_gap_s = 0.1;
  double max_extrapolation_s = 0.0;

  /// Key, constraint, unit and meaning of each field (common/param_schema.hpp).
  static const ParamSchema<PoseBufferParams>& schema();
  void validate() const;  ///< throws ParamError naming the field and its value
};

class PoseBuffer {
 public:
  enum class Status { kOk, kEmpty, kBeforeHistory, kAfterNewest, kGap };

  explicit PoseBuffer(const PoseBufferParams& params = {});

  /// Inserts a sample in time order; a sample with the utime of one held replaces it. Returns
  /// false (and ignores it) when it is older than the history window.
  bool add(const PoseSample& sample);

  /// Pose at `utime`: linear in position and velocity, slerp in orientation between the two
  /// neighbouring samples; constant-velocity extrapolation up to max_extrapolation_s past the
  /// newest. Never extrapolates before the oldest sample or across a gap > max_gap_s.
  std::optional<PoseSample> at(int64_t utime) const;
  /// As at(), with the reason for a refusal.
  Status lookup(int64_t utime, PoseSample* out) const;

  size_t size() const { return samples_.size(); }
  bool empty() const { return samples_.empty(); }
  int64_t oldest_utime() const { return samples_.front().utime; }
  int64_t newest_utime() const { return samples_.back().utime; }
  const PoseSample& newest() const { return samples_.back(); }

 private:
  PoseBufferParams params_;
  std::deque<PoseSample> samples_;
};

/// Interpolates between a and b at fraction s in [0, 1] (positions linear, orientation slerp).
PoseSample interpolate(const PoseSample& a, const PoseSample& b, double s);

}  // namespace alight
