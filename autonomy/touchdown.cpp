#include "autonomy/touchdown.hpp"

#include <algorithm>
#include <cmath>

namespace alight::autonomy {

void TouchdownDetector::arm(int64_t /*now_utime*/) {
  armed_ = true;
  detected_ = false;
  cue_ = "";
  peak_excess_mps2_ = 0.0;
  still_since_.reset();
  contact_z_m_.reset();
  last_z_m_.reset();
  impact_utime_.reset();
  poses_since_impact_ = 0;
}

void TouchdownDetector::add_imu(const ImuSample& imu) {
  if (!armed_ || detected_) return;
  const double excess = imu.accel_B.norm() - g_;
  peak_excess_mps2_ = std::max(peak_excess_mps2_, excess);
  const bool within_reach =
      !contact_z_m_ || (last_z_m_ && *last_z_m_ <= *contact_z_m_ + kImpactReachM);
  if (impact_utime_ && (imu.utime - *impact_utime_) * 1e-6 > kImpactConfirmS) {
    // No pose in the window: a blind descent, the impact is all there is. Poses that never
    // showed the body stopped: it was no touch-down.
    if (poses_since_impact_ == 0) {
      detected_ = true;
      cue_ = "impact";
      return;
    }
    impact_utime_.reset();
  }
  if (excess > params_.touchdown_accel_mps2 && within_reach) {
    if (confirm_ && !contact_z_m_) {
      if (!impact_utime_) {
        impact_utime_ = imu.utime;
        poses_since_impact_ = 0;
      }
      return;
    }
    detected_ = true;
    cue_ = "impact";
  }
}

void TouchdownDetector::add_pose(const PoseSample& pose, double z_setpoint_m, int64_t now_utime) {
  if (!armed_ || detected_) return;
  last_z_m_ = pose.p_W_B.z();
  if (impact_utime_) {
    ++poses_since_impact_;
    if (std::abs(pose.v_W_B.z()) <= kImpactStoppedMps) {
      detected_ = true;
      cue_ = "impact";
      return;
    }
  }
  const bool blocked = z_setpoint_m < pose.p_W_B.z() - 0.1 && std::abs(pose.v_W_B.z()) < 0.05;
  if (!blocked) {
    still_since_.reset();
    return;
  }
  if (!still_since_) still_since_ = now_utime;
  if ((now_utime - *still_since_) * 1e-6 >= params_.touchdown_still_s) {
    detected_ = true;
    cue_ = "resting";
  }
}

}  // namespace alight::autonomy
