// alight-estimator: IMU + RANGE + BARO + FLOW_CAMERA -> STATE_ESTIMATE and ESTIMATE_POSE (issue
// 17, the paper's future work: flying without motion capture). Glue only: the filter and the flow
// front end are estimator::Onboard (pure); this file owns LCM, the parameters and the logging.
//
// The flow takes the vehicle file's downward camera on FLOW_CAMERA: alight-sim --flow-camera
// renders it there while CAMERA carries the forward one (ingress); where the mission's camera is
// the downward one (landing), `--remap FLOW_CAMERA=CAMERA` reads that in its place.
//
// Runs on the utime of its inputs, so a replayed log gives the same estimates. Publishes one
// estimate per IMU sample fused, once static alignment has finished.

#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>

#include "common/camera_mount.hpp"
#include "common/image_msg.hpp"
#include "common/msg_convert.hpp"
#include "common/node.hpp"
#include "common/params.hpp"
#include "estimator/convert.hpp"
#include "estimator/onboard.hpp"
#include "estimator/params.hpp"

int main(int argc, char** argv) {
  using namespace alight;
  return run_node_main("alight-estimator", [&]() -> int {
    CLI::App app{
        "alight estimator: onboard state from IMU, rangefinder, barometer and the downward "
        "camera (IMU, RANGE, BARO, FLOW_CAMERA -> STATE_ESTIMATE, ESTIMATE_POSE)"};
    NodeArgs args;
    args.add_to(app, true);
    try {
      app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
      return app.exit(e);
    }
    args.finalize();

    const ParamNode root = ParamNode::load_file(args.config);
    const estimator::EstimatorParams params = estimator::load_estimator_params(root);
    const CameraMount mount = load_camera_mount(root, "downward");
    const CameraModel camera = load_camera_info(mount.camera_info_path);
    estimator::Onboard onboard(params, camera);

    Node node(args, "alight-estimator");
    const auto accept_stamp = [&](const char* ch, int64_t utime) {
      return node.accept_stamp(ch, utime);
    };
    const auto count = [&](const char* ch, estimator::Outcome o) {
      if (o != estimator::Outcome::kFused && o != estimator::Outcome::kQueued &&
          o != estimator::Outcome::kNotInitialised)
        node.reject_value(ch, estimator::to_string(o));
    };
    int64_t seq = 0;
    estimator::Health last_health = estimator::Health::kLost;
    uint32_t last_reasons = ~0u;
    int64_t last_velocity_resets = 0;
    node.on<imu_t>(channels::kImu, [&](const imu_t& m) {
      if (!accept_stamp(channels::kImu, m.utime)) return;
      const estimator::ImuSample imu = estimator::from_msg(m);
      const estimator::Outcome o = onboard.add_imu(imu);
      count(channels::kImu, o);
      if (o != estimator::Outcome::kFused) return;
      const estimator::State s = onboard.state();
      if (!s.initialised) return;
      if (s.health != last_health || s.health_reasons != last_reasons) {
        spdlog::info("estimator: {} ({})", estimator::to_string(s.health),
                     estimator::health_reasons_text(s.health_reasons));
        last_health = s.health;
        last_reasons = s.health_reasons;
      }
      if (s.counters.flow_velocity_resets != last_velocity_resets) {
        last_velocity_resets = s.counters.flow_velocity_resets;
        spdlog::warn(
            "estimator: horizontal velocity set to the flow's (the flow refused for {} s; "
            "{} resets so far)",
            params.health.flow_timeout_s, last_velocity_resets);
      }
      node.publish(channels::kStateEstimate, estimator::to_msg(s, imu.gyro_B, seq));
      node.publish(channels::kEstimatePose, estimator::to_pose_msg(s, imu.gyro_B, seq));
      ++seq;
    });
    node.on<range_t>(channels::kRange, [&](const range_t& m) {
      if (!accept_stamp(channels::kRange, m.utime)) return;
      count(channels::kRange, onboard.add_range(estimator::from_msg(m)));
    });
    node.on<baro_t>(channels::kBaro, [&](const baro_t& m) {
      if (!accept_stamp(channels::kBaro, m.utime)) return;
      count(channels::kBaro, onboard.add_baro(estimator::from_msg(m)));
    });
    estimator::FlowReason last_flow = estimator::FlowReason::kNoPrevious;
    node.on<image_t>(channels::kFlowCamera, [&](const image_t& m) {
      if (!accept_stamp(channels::kFlowCamera, m.utime)) return;
      std::string error;
      const auto image = image_from_msg(m, true, &error);
      if (!image) {
        node.reject_value(channels::kFlowCamera, error);
        return;
      }
      const estimator::FrameOutcome o = onboard.add_frame(image->pixels, image->utime);
      if (onboard.last_frame().flow != last_flow) {
        last_flow = onboard.last_frame().flow;
        spdlog::info("estimator: flow {}", estimator::to_string(last_flow));
      }
      if (o.dropped) node.reject_value(channels::kFlowCamera, "frame queue full (IMU stalled?)");
      if (o.processed > 0) count(channels::kFlowCamera, o.fused);
    });
    node.every(10.0, [&](int64_t) {
      const estimator::State s = onboard.state();
      spdlog::info("estimator: {} ({}), p_W [{:.2f} {:.2f} {:.2f}] m, terrain {:.2f} m",
                   estimator::to_string(s.health), estimator::health_reasons_text(s.health_reasons),
                   s.p_W_B.x(), s.p_W_B.y(), s.p_W_B.z(), s.terrain_height_m);
    });
    spdlog::info("alight-estimator: camera {} ({}x{}) on {}, publishing {} and {}", mount.name,
                 camera.width, camera.height, node.channel_name(channels::kFlowCamera),
                 channels::kStateEstimate, channels::kEstimatePose);
    return node.run();
  });
}
