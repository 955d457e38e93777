#pragma once
// The vision node's per-frame work for the in-process closed loop (closed_loop.hpp,
// camera_vision): the pipeline on the frame with the pose interpolated at its exposure, then the
// node's message conversion (VISION_TARGET) and autonomy's. Used by the closed-loop tests with
// real vision (test/integration) and the benches that fly them (bench/estimator).

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>

#include "autonomy/types.hpp"
#include "common/camera_model.hpp"
#include "common/pose_buffer.hpp"
#include "sim/simulator.hpp"

namespace alight::vision {
class Pipeline;
struct PipelineParams;
}  // namespace alight::vision

namespace alight::autonomy::test {

class RealVision {
 public:
  /// The vehicle file's vision parameters and the mission's camera (downward for landing).
  RealVision(const std::string& vehicle_file, Mission mission);
  /// ... with `adjust` applied to the vehicle file's pipeline parameters (a rule switched off).
  RealVision(const std::string& vehicle_file, Mission mission,
             const std::function<void(vision::PipelineParams&)>& adjust);
  /// ... undistorting with `model` instead of the vehicle file's (the scenario's lens,
  /// sim::with_lens: the camera the simulator rendered).
  RealVision(const std::string& vehicle_file, Mission mission,
             const std::function<void(vision::PipelineParams&)>& adjust,
             const std::optional<CameraModel>& model);
  ~RealVision();
  std::optional<TargetMeasurement> operator()(const sim::CameraFrame& f,
                                              const std::optional<PoseSample>& pose);

  int frames = 0;          ///< frames processed
  int found = 0;           ///< ... in which the target was found
  int partial = 0;         ///< ... reported as a partial view (autonomy refines on these too)
  int platform_found = 0;  ///< ... in which a moving top was measured (VISION_PLATFORM found)
  /// The last frame's moving-top measurement (VISION_PLATFORM, found, through the node's and
  /// autonomy's conversions), once.
  std::optional<PlatformMeasurement> take_platform() { return std::exchange(platform_, {}); }

 private:
  std::unique_ptr<vision::Pipeline> pipeline_;
  std::optional<PlatformMeasurement> platform_;
};

}  // namespace alight::autonomy::test
