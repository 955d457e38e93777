// alight-vision: CAMERA + MOCAP_POSE -> VISION_TARGET (one per processed frame, also when
// nothing was found, with the reason) and VISION_DIAG (JPEG, lower rate). Paper 3.1-3.3.
//
// Frames: CAMERA messages are processed in the order they arrived. A frame needs
// the pose at its exposure time; when the newest motion-capture sample is still older than the
// frame, the frame waits for it, with the frames after it, until the camera has run on
// max_pose_wait_s of exposure time without it (then it is processed without a pose:
// REASON_NO_POSE) - vision/node/frame_pose_pairing.hpp. Nothing here reads a clock, and everything
// published is stamped with the frame's exposure time, so the output is a function of the
// message sequence alone: a replayed log gives the same bytes however busy the machine is.
//
// Keeping up with the camera: CAMERA messages wait undecoded in the node's queue
// (Node::on, at most vision.camera_queue_frames; more are dropped and counted), then decoded
// frames wait in the pairing for their pose (at most 64, FramePosePairing's bound; a frame
// beyond it is processed without a pose, never dropped). The first queue fills only when
// processing is slower than the camera, the second only when poses stop while frames come.
// For every processed frame VISION_TIMING (vision_timing_t) says how long it waited, how long
// Pipeline::process took and what the node counted so far; it is measured on the steady and
// wall clocks, so it is a channel of its own and VISION_TARGET stays a function of the input.
//
// Bounded latency: a loaded computer can leave the vision seconds behind the camera, and a
// target seconds old describes where the vehicle was, not where it is (autonomy lost the
// platform in the refinement on such targets). A frame whose turn comes more than
// max_pose_wait_s + kLateMarginS after the node read it is skipped unprocessed and counted
// (frames_late): no VISION_TARGET, so the pipeline catches up with the camera at once. This is
// the one choice that depends on the machine; scripts/replay-vision replays the frames the live
// vision processed (those with a VISION_TARGET in the log), so a replay makes the same choice.
//
// Input boundary (vision/node/inputs.hpp): a pose with a non-finite value or a non-unit
// quaternion is refused, and so is any message whose stamp the node's StampGuard refuses (a
// pose an hour ahead used to push every later pose out of the buffer); a frame that does not
// decode safely is reported as REASON_BAD_IMAGE. An exception out of one frame's work (OpenCV,
// out of memory) drops that frame, is counted (NODE_STATUS: CAMERA rejected_values, and the
// periodic log line) and never ends the process. None of this reads a clock into what is
// computed: a replayed log still gives byte-identical output.

#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <alight/image_t.hpp>
#include <alight/pose_t.hpp>
#include <alight/target_t.hpp>
#include <alight/vision_timing_t.hpp>
#include <ctime>
#include <opencv2/core.hpp>
#include <optional>

#include "common/camera_mount.hpp"
#include "common/image_msg.hpp"
#include "common/msg_convert.hpp"
#include "common/node.hpp"
#include "vision/node/convert.hpp"
#include "vision/node/diag_image.hpp"
#include "vision/node/frame_pose_pairing.hpp"
#include "vision/node/inputs.hpp"
#include "vision/pipeline.hpp"

using namespace alight;
using namespace alight::vision;

namespace {
// What a frame may wait beyond its pose wait before it is too old to act on: 0.3 s is nine
// frames at 30 Hz, 12 cm of the search path at 0.4 m/s, and well beyond the few frames a
// healthy vision ever has queued [s].
constexpr double kLateMarginS = 0.3;

// CPU time of the calling thread [us]: a frame's own cost, apart from the time other processes
// held the core (the machine is shared).
int64_t thread_cpu_us() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1'000'000 + ts.tv_nsec / 1000;
}
}  // namespace

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

    // One frame at a time on this thread: OpenCV's worker threads (TBB) would only add their
    // hand-offs and spinning to a 640x480 frame's work and compete with the camera and the
    // other nodes for the cores, and it leaves process_cpu_us the whole of a frame's
    // CPU time. Pixel results do not depend on the thread count.
    cv::setNumThreads(1);
    const Mission mission = mission_from_string(mission_name);
    const ParamNode root = ParamNode::load_file(args.config);
    const NodeParams params = load_node_params(root);
    const CameraMount mount =
        load_camera_mount(root, mission == Mission::kLanding ? "downward" : "forward");
    const CameraModel camera = load_camera_info(mount.camera_info_path);
    Pipeline pipeline(mission, params.pipeline, camera, mount);
    Node node(args, "alight-vision");
    spdlog::info("alight-vision: mission {}, camera {} ({}x{}, f {:.1f} px)", mission_name,
                 mount.name, camera.width, camera.height, camera.fx);

    struct Pending {
      Image image;
      bool bad = false;
      Receipt receipt;  // when the node read it off LCM (timing only)
    };
    FramePosePairing<Pending> pairing(params.poses,
                                      static_cast<int64_t>(params.max_pose_wait_s * 1e6));
    int64_t last_diag_utime = 0;
    uint64_t n_found = 0, n_frames = 0, n_late = 0;
    const int64_t max_wait_us = static_cast<int64_t>((params.max_pose_wait_s + kLateMarginS) * 1e6);

    uint64_t n_frame_errors = 0;
    const StampCheck accept_stamp = [&](const std::string& channel, int64_t utime) {
      return node.accept_stamp(channel, utime);
    };
    const RejectValue reject = [&](const std::string& channel, const std::string& why) {
      node.reject_value(channel, why);
    };

    const auto timing_message = [&](const Pending& f, const FrameResult& r, PairingOutcome outcome,
                                    int64_t start_steady, int64_t process_us,
                                    int64_t process_cpu_us) {
      const ChannelStats& c = node.stats(channels::kCamera);
      vision_timing_t t{};
      t.utime = r.utime;
      t.seq = r.seq;
      t.receive_utime = f.receipt.wall_utime;
      t.wait_us = start_steady - f.receipt.steady_utime;
      t.process_us = process_us;
      t.process_cpu_us = process_cpu_us;
      t.publish_utime = wall_utime();
      t.total_us = steady_utime() - f.receipt.steady_utime;
      switch (outcome) {
        case PairingOutcome::kWithPose:
          t.pose = vision_timing_t::POSE_OK;
          break;
        case PairingOutcome::kPoseTimedOut:
          t.pose = vision_timing_t::POSE_TIMED_OUT;
          break;
        case PairingOutcome::kPoseUnavailable:
          t.pose = vision_timing_t::POSE_UNAVAILABLE;
          break;
        case PairingOutcome::kQueueFull:
          t.pose = vision_timing_t::POSE_QUEUE_FULL;
          break;
      }
      t.frames_received = static_cast<int64_t>(c.received + c.decode_errors + c.dropped);
      t.frames_dropped = static_cast<int64_t>(c.dropped);
      t.frames_refused = static_cast<int64_t>(c.decode_errors + c.rejected_stamps);
      t.frames_failed = static_cast<int64_t>(n_frame_errors);
      t.frames_late = static_cast<int64_t>(n_late);
      t.frames_processed = static_cast<int64_t>(n_frames);
      t.frames_waiting = static_cast<int32_t>(pairing.waiting());
      return t;
    };
    const auto process = [&](const Pending& f, const std::optional<PoseSample>& pose,
                             PairingOutcome outcome) {
      const int64_t waited_us = steady_utime() - f.receipt.steady_utime;
      if (waited_us > max_wait_us) {
        ++n_late;
        if (n_late == 1 || n_late % 100 == 0)
          spdlog::warn(
              "{} frame(s) skipped as too old to act on (last: waited {:.0f} ms, bound {:.0f} "
              "ms): the vision is behind the camera",
              n_late, waited_us * 1e-3, max_wait_us * 1e-3);
        return;
      }
      // Nothing is published before the frame's work is through, so a frame that throws
      // half-way is dropped whole.
      const auto error = run_guarded([&] {
        const int64_t start = steady_utime(), start_cpu = thread_cpu_us();
        const FrameResult r = f.bad ? pipeline.process(cv::Mat(), f.image.utime, pose)
                                    : pipeline.process(f.image.pixels, f.image.utime, pose,
                                                       f.image.exposure_s, f.image.line_delay_s);
        const int64_t process_us = steady_utime() - start;
        const int64_t process_cpu_us = thread_cpu_us() - start_cpu;
        const target_t target = to_msg(r);
        std::optional<image_t> diag;
        if (params.diag_rate_hz > 0 &&
            r.utime - last_diag_utime >= static_cast<int64_t>(1e6 / params.diag_rate_hz)) {
          diag = jpeg_image_to_msg(draw_diag_image(f.image.pixels, r), r.utime,
                                   params.diag_jpeg_quality);
          last_diag_utime = r.utime;
        }
        node.publish(channels::kVisionTarget, target);
        if (const auto platform = to_platform_msg(r))
          node.publish(channels::kVisionPlatform, *platform);
        if (diag) node.publish(channels::kVisionDiag, *diag);
        ++n_frames;
        if (r.found()) ++n_found;
        node.publish(channels::kVisionTiming,
                     timing_message(f, r, outcome, start, process_us, process_cpu_us));
        spdlog::debug("frame {} utime {}: {} ({} features, {} matches)", r.seq, r.utime,
                      to_string(r.reason), r.n_features, r.n_matches);
      });
      if (error) {
        ++n_frame_errors;
        reject(channels::kCamera, "frame " + std::to_string(f.image.utime) + " dropped: " + *error);
      }
    };
    const auto try_process = [&]() {
      while (auto r = pairing.poll()) {
        if (r->outcome != PairingOutcome::kWithPose)
          spdlog::debug("frame {} without a pose: {}", r->utime, to_string(r->outcome));
        process(r->frame, r->pose, r->outcome);
      }
    };

    node.on<pose_t>(channels::kMocapPose, [&](const pose_t& msg) {
      if (add_mocap_pose(msg, pairing.poses(), accept_stamp, reject)) try_process();
    });
    node.on<image_t>(
        channels::kCamera,
        [&](const image_t& msg) {
          FrameInput in = camera_frame(msg, accept_stamp, reject);
          if (!in.use) return;
          Pending f;
          f.receipt = node.receipt();
          if (in.image) {
            f.image = std::move(*in.image);
          } else {
            f.image.utime = msg.utime;
            f.bad = true;
          }
          const int64_t utime = f.image.utime;
          pairing.add_frame(std::move(f), utime);
          try_process();
        },
        static_cast<size_t>(params.camera_queue_frames));
    node.every(10.0, [&](int64_t) {
      const ChannelStats& c = node.stats(channels::kCamera);
      spdlog::info(
          "{} frames, {} with a target, {} without a pose ({} timed out, {} not in the history, "
          "{} behind a full queue), {} refused (image or stamp), {} dropped by an exception, "
          "{} dropped by a full input queue, {} skipped too old",
          n_frames, n_found,
          pairing.counts().timed_out + pairing.counts().unavailable + pairing.counts().queue_full,
          pairing.counts().timed_out, pairing.counts().unavailable, pairing.counts().queue_full,
          c.rejected_values + c.rejected_stamps, n_frame_errors, c.dropped, n_late);
    });
    // Said once subscribed: what is published before this is not heard (scripts/replay-vision
    // waits for it).
    spdlog::info("alight-vision: listening on {} and {}", node.channel_name(channels::kCamera),
                 node.channel_name(channels::kMocapPose));
    return node.run();
  });
}
