// alight-vision-eval LOG --config VEHICLE [--mission landing|ingress]: runs the vision pipeline
// (paper 3.1-3.3) offline over the CAMERA frames of a session log, each with the pose
// interpolated at its exposure time (motion capture's, or the onboard estimate's on a flight
// without it), and says what it saw. Unlike the live node it never drops a frame, so it measures
// the pipeline alone. For every log: how the camera delivered the frames (rate, gaps, repeated
// stamps, jitter, delay to the recorder), how they were exposed, the features and matches, the
// per-reason histogram (the frames each stage or gate refused, with what to check for the
// reasons a camera or its set-up causes) and the processing time per frame on this machine
// (tools/vision_eval.hpp). With the simulator's truth (SIM_TRUTH) also the waypoint and height
// errors (median, p90). --frames prints every frame's whole result at full precision and no
// timing, so two builds' outputs compare with diff (a refactor of the vision must leave them
// identical).
//
// Exit status: 0 when the log was read, 2 when it cannot be read or holds no CAMERA frames.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <alight/image_t.hpp>
#include <alight/pose_t.hpp>
#include <alight/sim_truth_t.hpp>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <optional>
#include <vector>

#include "common/camera_mount.hpp"
#include "common/channels.hpp"
#include "common/decode.hpp"
#include "common/image_msg.hpp"
#include "common/msg_convert.hpp"
#include "common/params.hpp"
#include "tools/vision_eval.hpp"
#include "vision/frame_line.hpp"
#include "vision/pipeline.hpp"

namespace {

using namespace alight;
using namespace alight::vision;

template <class T>
bool decode(const lcm::LogEvent& ev, T& msg) {
  return ev.datalen >= 0 && alight::decode_message(msg, ev.data, static_cast<size_t>(ev.datalen));
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"alight-vision-eval: the vision pipeline over a session log, scored against truth"};
  std::string log_path, config, mission_name = "landing", pose_channel = "auto";
  bool verbose = false, frames_out = false;
  app.add_option("log", log_path, "Session log (.lcmlog) with CAMERA, MOCAP_POSE, SIM_TRUTH")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--config", config, "Vehicle file (camera mount, vision section)")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--mission", mission_name, "landing | ingress")
      ->check(CLI::IsMember({"landing", "ingress"}));
  app.add_option("--pose-channel", pose_channel,
                 "pose_t channel the frames' poses come from; auto: MOCAP_POSE when the log has "
                 "it, else ESTIMATE_POSE (a flight without motion capture)");
  app.add_flag("-v,--verbose", verbose, "One line per frame");
  app.add_flag("--frames", frames_out,
               "One line per frame with its whole result, exact and without timing (to compare)");
  CLI11_PARSE(app, argc, argv);

  try {
    const Mission mission = mission_from_string(mission_name);
    const ParamNode root = ParamNode::load_file(config);
    const NodeParams params = load_node_params(root);
    const CameraMount mount =
        load_camera_mount(root, mission == Mission::kLanding ? "downward" : "forward");
    const CameraModel camera = load_camera_info(mount.camera_info_path);

    // Pass 1: every pose (a frame may need one logged after it) and the truth.
    lcm::LogFile log(log_path, "r");
    if (!log.good()) {
      std::fprintf(stderr, "alight-vision-eval: cannot read %s\n", log_path.c_str());
      return 2;
    }
    PoseBufferParams pb = params.poses;
    pb.history_s = 1e6;
    std::map<std::string, PoseBuffer> poses_by_channel;
    for (const char* ch : {channels::kMocapPose, channels::kEstimatePose})
      poses_by_channel.emplace(ch, PoseBuffer(pb));
    if (pose_channel != "auto") poses_by_channel.emplace(pose_channel, PoseBuffer(pb));
    std::optional<sim_truth_t> truth;
    for (const lcm::LogEvent* ev = log.readNextEvent(); ev; ev = log.readNextEvent()) {
      if (const auto it = poses_by_channel.find(ev->channel); it != poses_by_channel.end()) {
        pose_t m;
        if (decode(*ev, m)) {
          if (const auto p = pose_from_msg(m, nullptr)) it->second.add(*p);
        }
      } else if (ev->channel == channels::kSimTruth && !truth) {
        sim_truth_t m;
        if (decode(*ev, m)) truth = m;
      }
    }

    if (pose_channel == "auto")
      pose_channel = poses_by_channel.at(channels::kMocapPose).empty() &&
                             !poses_by_channel.at(channels::kEstimatePose).empty()
                         ? channels::kEstimatePose
                         : channels::kMocapPose;
    const PoseBuffer& poses = poses_by_channel.at(pose_channel);
    std::printf("poses: %s (%zu)%s\n", pose_channel.c_str(), poses.size(),
                truth ? "" : "; truth: none (no SIM_TRUTH: a real session, no errors to score)");

    // Pass 2: the frames in log order.
    lcm::LogFile log2(log_path, "r");
    Pipeline pipeline(mission, params.pipeline, camera, mount);
    std::vector<tools::EvalFrame> frames;
    std::vector<double> lateral_m, height_m, size_err_m;
    for (const lcm::LogEvent* ev = log2.readNextEvent(); ev; ev = log2.readNextEvent()) {
      if (ev->channel != channels::kCamera) continue;
      image_t msg;
      if (!decode(*ev, msg)) continue;
      std::string error;
      const auto img = image_from_msg(msg, true, &error);
      if (!img) {
        std::fprintf(stderr, "alight-vision-eval: frame %lld not decoded: %s\n",
                     static_cast<long long>(msg.utime), error.c_str());
        continue;
      }
      const std::optional<PoseSample> pose = poses.at(img->utime);
      const auto t0 = std::chrono::steady_clock::now();
      const FrameResult r =
          pipeline.process(img->pixels, img->utime, pose, img->exposure_s, img->line_delay_s);
      tools::EvalFrame f;
      f.process_ms =
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      f.utime = img->utime;
      f.log_utime = ev->timestamp;
      f.reason = r.reason;
      f.n_features = r.n_features;
      f.n_matches = r.n_matches;
      f.n_inliers = r.target.n_inliers_target;
      f.has_pose = pose.has_value();
      if (!img->pixels.empty()) f.exposure = tools::measure_exposure(img->pixels);
      f.exposure_s = img->exposure_s;
      frames.push_back(f);
      if (frames_out) std::fputs(frame_line(r).c_str(), stdout);
      double lat = -1, dh = 0;
      if (truth && (r.found() || located_only(r.reason))) {
        const double* c =
            mission == Mission::kLanding ? truth->platform_center_W : truth->opening_center_W;
        const Vector3d c_W(c[0], c[1], c[2]);
        lat = mission == Mission::kLanding ? (r.target.p_W - c_W).head<2>().norm()
                                           : (r.target.p_W - c_W).tail<2>().norm();
        dh = mission == Mission::kLanding ? r.target.height_m - truth->platform_size_m[2]
                                          : r.target.size_m[0] - truth->opening_size_m[0];
        if (r.found()) {
          lateral_m.push_back(lat);
          (mission == Mission::kLanding ? height_m : size_err_m).push_back(dh);
        }
      }
      if (verbose) {
        const PoseSample p = pose.value_or(PoseSample{});
        std::printf("%lld %-26s feat %3d match %3d in %3d/%3d base %.3f", (long long)r.utime,
                    to_string(r.reason), r.n_features, r.n_matches, r.target.n_inliers_dominant,
                    r.target.n_inliers_target, r.baseline_m);
        if (lat >= 0)
          std::printf(" err %.3f d%s %+.3f size %.2fx%.2f px (%.0f, %.0f)", lat,
                      mission == Mission::kLanding ? "h" : "w", dh, r.target.size_m[0],
                      r.target.size_m[1], r.target.pixel.x(), r.target.pixel.y());
        std::printf(" level %.0f clip %.2f", f.exposure.level, f.exposure.clipped);
        if (f.exposure_s) std::printf(" exp %.2f ms", *f.exposure_s * 1e3);
        std::printf(" body (%.2f, %.2f, %.2f) %.1f ms\n", p.p_W_B.x(), p.p_W_B.y(), p.p_W_B.z(),
                    f.process_ms);
      }
    }
    if (frames.empty()) {
      std::fprintf(stderr, "alight-vision-eval: no CAMERA frames in %s\n", log_path.c_str());
      return 2;
    }
    std::fputs(tools::format_summary(tools::summarize(frames)).c_str(), stdout);
    if (!lateral_m.empty()) {
      std::printf("waypoint_error_m: median %.4f p90 %.4f max %.4f (n %zu)\n",
                  tools::percentile(lateral_m, 0.5), tools::percentile(lateral_m, 0.9),
                  tools::percentile(lateral_m, 1.0), lateral_m.size());
      const auto& e = mission == Mission::kLanding ? height_m : size_err_m;
      std::vector<double> a;
      for (double x : e) a.push_back(std::abs(x));
      std::printf("%s: median %+.4f |p90| %.4f\n",
                  mission == Mission::kLanding ? "height_error_m" : "width_error_m",
                  tools::percentile(e, 0.5), tools::percentile(a, 0.9));
    }
    return 0;
  } catch (const ParamError& e) {
    std::fprintf(stderr, "alight-vision-eval: %s\n", e.what());
    return 2;
  }
}
