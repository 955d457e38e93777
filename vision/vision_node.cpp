// alight-vision: CAMERA + MOCAP_POSE -> VISION_TARGET (one per processed frame, also when
// nothing was found, with the reason) and VISION_DIAG (JPEG, lower rate). Paper 3.1-3.3.
//
// Frames: CAMERA is subscribed with on_latest, so when processing falls behind the node takes
// the newest frame and skips the rest. A frame needs the pose at its exposure time; when the
// newest motion-capture sample is still older than the frame, the frame waits for it (at most
// max_pose_wait_s, then it is processed without a pose: REASON_NO_POSE). Everything published
// is stamped with the frame's exposure time, so a replayed log gives the same sequence.

#include <alight/image_t.hpp>
#include <alight/pose_t.hpp>
#include <alight/target_t.hpp>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <optional>

#include "common/camera_mount.hpp"
#include "common/msg_convert.hpp"
#include "common/node.hpp"
#include "vision/convert.hpp"
#include "vision/diag_image.hpp"
#include "vision/pipeline.hpp"

using namespace alight;
using namespace alight::vision;

int main(int argc, char** argv) {
  return alight::run_node_main("alight-vision", [&]() -> int {
    CLI::App app{"alight vision: platform / opening waypoints from the camera (paper 3.1-3.3)"};
    NodeArgs args;
    args.add_to(app, true);
    std::string mission_name = "landing";
    app.add_option("--mission", mission_name, "landing | ingress")
        ->check(CLI::IsMember({"landing", "ingress"}));
    try {
      app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
      return app.exit(e);
    }
    args.finalize();

    const Mission mission = mission_from_string(mission_name);
    const ParamNode root = ParamNode::load_file(args.config);
    const NodeParams params = load_node_params(root);
    const CameraMount mount =
        load_camera_mount(root, mission == Mission::kLanding ? "downward" : "forward");
    const CameraModel camera = load_camera_info(mount.camera_info_path);
    Pipeline pipeline(mission, params.pipeline, camera, mount);
    PoseBuffer poses(params.poses);
    Node node(args.lcm_url, "alight-vision");
    spdlog::info("alight-vision: mission {}, camera {} ({}x{}, f {:.1f} px)", mission_name,
                 mount.name, camera.width, camera.height, camera.fx);

    struct Pending {
      Image image;
      int64_t arrived_wall = 0;
      bool bad = false;
    };
    std::optional<Pending> pending;
    int64_t last_diag_utime = 0;
    uint64_t n_found = 0, n_frames = 0;

    const auto process = [&](const Pending& f, const std::optional<PoseSample>& pose) {
      const FrameResult r = f.bad ? pipeline.process(cv::Mat(), f.image.utime, pose)
                                  : pipeline.process(f.image.pixels, f.image.utime, pose);
      node.publish("VISION_TARGET", to_msg(r));
      ++n_frames;
      if (r.found()) ++n_found;
      spdlog::debug("frame {} utime {}: {} ({} features, {} matches)", r.seq, r.utime,
                    to_string(r.reason), r.n_features, r.n_matches);
      if (params.diag_rate_hz > 0 &&
          r.utime - last_diag_utime >= static_cast<int64_t>(1e6 / params.diag_rate_hz)) {
        last_diag_utime = r.utime;
        node.publish("VISION_DIAG", jpeg_image_to_msg(draw_diag_image(f.image.pixels, r), r.utime,
                                                      params.diag_jpeg_quality));
      }
    };
    const auto try_process = [&]() {
      if (!pending) return;
      PoseSample pose;
      const auto status = poses.lookup(pending->image.utime, &pose);
      if (status == PoseBuffer::Status::kOk) {
        const Pending f = std::move(*pending);
        pending.reset();
        process(f, pose);
        return;
      }
      const bool may_come = status == PoseBuffer::Status::kAfterNewest ||
                            status == PoseBuffer::Status::kEmpty;
      if (may_come &&
          wall_utime() - pending->arrived_wall < static_cast<int64_t>(params.max_pose_wait_s * 1e6))
        return;  // wait for the pose
      const Pending f = std::move(*pending);
      pending.reset();
      process(f, std::nullopt);
    };

    node.on<pose_t>("MOCAP_POSE", [&](const pose_t& msg) {
      poses.add(from_msg(msg));
      try_process();
    });
    node.on_latest<image_t>("CAMERA", [&](const image_t& msg) {
      std::string error;
      Pending f;
      f.arrived_wall = wall_utime();
      if (auto img = image_from_msg(msg, true, &error)) {
        f.image = std::move(*img);
      } else {
        spdlog::warn("CAMERA frame {}: {}", msg.utime, error);
        f.image.utime = msg.utime;
        f.bad = true;
      }
      if (pending) spdlog::debug("frame {} skipped: no pose for it yet", pending->image.utime);
      pending = std::move(f);
      try_process();
    });
    node.every(0.02, [&](int64_t) { try_process(); });
    node.every(10.0, [&](int64_t) {
      spdlog::info("{} frames, {} with a target, {} camera frames skipped", n_frames, n_found,
                   node.stats("CAMERA").skipped);
    });
    return node.run();
  });
}
