#include "real_vision.hpp"

#include "autonomy/convert.hpp"
#include "sim/params.hpp"
#include "vision/node/convert.hpp"
#include "vision/params.hpp"
#include "vision/pipeline.hpp"

namespace alight::autonomy::test {

RealVision::RealVision(const std::string& vehicle_file, Mission mission)
    : RealVision(vehicle_file, mission, [](vision::PipelineParams&) {}) {}

RealVision::RealVision(const std::string& vehicle_file, Mission mission,
                       const std::function<void(vision::PipelineParams&)>& adjust)
    : RealVision(vehicle_file, mission, adjust, std::nullopt) {}

RealVision::RealVision(const std::string& vehicle_file, Mission mission,
                       const std::function<void(vision::PipelineParams&)>& adjust,
                       const std::optional<CameraModel>& model) {
  auto params = vision::load_node_params(vehicle_file);
  adjust(params.pipeline);
  auto rig =
      sim::load_camera_rig(vehicle_file, mission == Mission::kLanding ? "downward" : "forward");
  if (model) rig.model = *model;
  pipeline_ = std::make_unique<vision::Pipeline>(
      mission == Mission::kLanding ? vision::Mission::kLanding : vision::Mission::kIngress,
      params.pipeline, rig.model, rig.mount);
}

RealVision::~RealVision() = default;

std::optional<TargetMeasurement> RealVision::operator()(const sim::CameraFrame& f,
                                                        const std::optional<PoseSample>& pose) {
  const auto r = pipeline_->process(f.pixels, f.utime, pose, f.exposure_s, f.line_delay_s);
  ++frames;
  found += r.found();
  const TargetMeasurement m = from_msg(vision::to_msg(r));
  partial += m.partial;
  platform_.reset();
  if (const auto pm = vision::to_platform_msg(r)) {
    std::string why;
    platform_ = platform_from_msg(*pm, &why);
    platform_found += platform_.has_value();
  }
  return m;
}

}  // namespace alight::autonomy::test
