#pragma once
// The onboard estimator as one pure object: the error-state EKF (estimator.hpp) fed by
// the IMU, the rangefinder, the barometer and the flow front end (flow_odometry.hpp) run on the
// downward camera's frames. What the front end needs from the filter is assembled here: the
// rotation between two frames from the bias-corrected gyro, and the floor's normal in the first
// frame's camera from the estimated attitude. The node (estimator_node.cpp) only converts
// messages and publishes; a test composes this with the simulator without LCM.

#include <cstdint>
#include <deque>
#include <opencv2/core.hpp>
#include <optional>

#include "common/camera_model.hpp"
#include "estimator/estimator.hpp"
#include "estimator/flow_odometry.hpp"

namespace alight::estimator {

/// What happened to a camera frame.
struct FrameOutcome {
  bool queued = false;   ///< waits for the IMU to reach its exposure time
  bool dropped = false;  ///< the frame queue was full (the IMU stalled): the oldest dropped
  FlowReason flow = FlowReason::kNoPrevious;  ///< the front end's verdict (when processed)
  Outcome fused = Outcome::kQueued;           ///< the filter's verdict on the flow sample
  std::optional<FlowSample> sample;           ///< the front end's sample (diagnostics)
  int processed = 0;                          ///< frames taken from the queue by this call
};

class Onboard {
 public:
  /// Throws ParamError on a bad configuration (parameters, camera).
  Onboard(const EstimatorParams& params, const CameraModel& camera);

  Outcome add_imu(const ImuSample& imu);
  Outcome add_range(const RangeSample& range) { return filter_.add_range(range); }
  Outcome add_baro(const BaroSample& baro) { return filter_.add_baro(baro); }
  /// A mono8 frame with its exposure time. Processed once the IMU has reached that time (the
  /// rotation since the previous frame must be known), in arrival order: here, or by the
  /// add_imu that reaches it.
  FrameOutcome add_frame(const cv::Mat& gray, int64_t utime);

  State state() const { return filter_.state(); }
  const FlowOdometry& flow() const { return flow_; }
  /// The verdicts on the last frame processed (by add_frame or by add_imu catching up).
  const FrameOutcome& last_frame() const { return last_; }
  /// Frames dropped because the queue was full.
  int64_t frames_dropped() const { return frames_dropped_; }

  /// Rotation R_B1B2 (body at t2 into body at t1) from the gyro samples minus `gyro_bias_B`;
  /// nullopt unless the samples cover [t1, t2]. Each IMU sample is the mean rate over the
  /// interval ending at its stamp (ImuSample).
  std::optional<Matrix3d> body_rotation(int64_t t1_utime, int64_t t2_utime,
                                        const Vector3d& gyro_bias_B) const;

 private:
  struct Frame {
    cv::Mat gray;
    int64_t utime = 0;
  };
  FrameOutcome process(const Frame& f);
  int drain();  ///< processes the queued frames the IMU has reached; how many

  EstimatorParams params_;
  Estimator filter_;
  FlowOdometry flow_;
  Matrix3d R_BC_;
  std::deque<ImuSample> imu_;  ///< the last imu_keep_s of samples, oldest first
  std::deque<Frame> frames_;   ///< waiting for the IMU
  std::optional<int64_t> prev_frame_utime_;
  int64_t frames_dropped_ = 0;
  FrameOutcome last_;
};

}  // namespace alight::estimator
