// alight-calibrate: camera intrinsics and distortion from chessboard views, written in the ROS
// camera_info YAML layout that vision and sim read (common/camera_model.hpp).
//
//   alight-calibrate --images calib/ --board 9x6 --square 0.025 --output config/cameras/mine.yaml
//   alight-calibrate --live --config config/cameras/usb_mono_640x480.yaml --views 20 --output ...
//
// Prints each view's reprojection RMS and the overall RMS [px]; a good calibration of a
// 640x480 camera is well under 0.5 px. Exit codes: 0 written, 1 failure (too few boards found,
// unreadable images), 2 bad command line or configuration, 3-6 as alight-camera for --live.

#include <spdlog/spdlog.h>
#include <time.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>

#include "camera_driver/calibration.hpp"
#include "camera_driver/params.hpp"
#include "camera_driver/stored_source.hpp"
#include "camera_driver/v4l2_capture.hpp"
#include "common/camera_model.hpp"
#include "common/node.hpp"
#include "common/params.hpp"

namespace {

using namespace alight;
using namespace alight::camera;

int64_t mono_now_us() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1000000 + ts.tv_nsec / 1000;
}

int exit_code(CaptureError e) {
  switch (e) {
    case CaptureError::kNotFound:
    case CaptureError::kDeviceLost:
      return 3;
    case CaptureError::kBusy:
      return 4;
    case CaptureError::kPermissionDenied:
      return 5;
    case CaptureError::kAmbiguous:
    case CaptureError::kNotCapture:
    case CaptureError::kFormatRejected:
      return 6;
    default:
      return 1;
  }
}

// Live views: a frame is kept when the board is found and at least `interval_s` has passed
// since the last kept one, so the user has time to move the board to a new pose.
int capture_live(const CameraParams& p, const ChessboardParams& board, int views, double interval_s,
                 std::vector<cv::Mat>& images, std::vector<std::string>& names) {
  auto io = make_linux_sys_io();
  CaptureConfig config = capture_config(p);
  config.encoding = OutputEncoding::kMono8;
  V4l2Capture cap(*io, config);
  const Status s = cap.open();
  if (!s.ok()) {
    spdlog::error("alight-calibrate: {}", s.message);
    return exit_code(s.error);
  }
  spdlog::info("alight-calibrate: show the board at {} poses (tilted, near the corners)", views);
  int64_t last_kept = 0;
  while (static_cast<int>(images.size()) < views && !Node::signalled()) {
    GrabResult g = cap.grab(200);
    if (g.status == GrabStatus::kDeviceLost || g.status == GrabStatus::kError) {
      spdlog::error("alight-calibrate: {}", g.message);
      return 1;
    }
    if (!g.frame) continue;
    const int64_t now = mono_now_us();
    if (now - last_kept < static_cast<int64_t>(interval_s * 1e6)) continue;
    if (!find_chessboard(g.frame->pixels, board)) continue;
    images.push_back(g.frame->pixels.clone());
    names.push_back("live " + std::to_string(images.size()));
    last_kept = now;
    spdlog::info("alight-calibrate: view {}/{} kept", images.size(), views);
  }
  return 0;
}

int run(int argc, char** argv) {
  CLI::App app{"alight-calibrate: chessboard intrinsics -> ROS camera_info YAML"};
  NodeArgs args;
  args.add_to(app, false);
  std::string images_dir, output, board_text = "9x6", name;
  double square_m = 0.025, interval_s = 1.5;
  bool live = false, k3 = false, no_tangential = false;
  int views = 20, min_views = 5;
  app.add_option("--images", images_dir, "Folder of chessboard images");
  app.add_flag("--live", live, "Capture views from the camera in --config instead");
  app.add_option("--views", views, "--live: views to capture")->check(CLI::PositiveNumber);
  app.add_option("--interval", interval_s, "--live: least time between kept views [s]");
  app.add_option("--board", board_text, "Inner corners COLSxROWS (squares minus one)");
  app.add_option("--square", square_m, "Square side [m]")->check(CLI::PositiveNumber);
  app.add_option("--output", output, "camera_info YAML to write")->required();
  app.add_option("--name", name, "camera_name in the file (default: output file stem)");
  app.add_flag("--k3", k3, "Estimate k3 too (wide-angle lenses)");
  app.add_flag("--no-tangential", no_tangential, "Hold p1 = p2 = 0");
  app.add_option("--min-views", min_views, "Least views with a board")->check(CLI::PositiveNumber);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int r = app.exit(e);
    return r == 0 ? 0 : 2;
  }
  args.finalize();

  ChessboardParams board;
  board.square_m = square_m;
  board.fix_k3 = !k3;
  board.fix_tangential = no_tangential;
  board.min_views = min_views;
  if (std::sscanf(board_text.c_str(), "%dx%d", &board.inner_cols, &board.inner_rows) != 2 ||
      board.inner_cols < 2 || board.inner_rows < 2)
    throw ParamError("--board", "", board_text, "expected inner corners as COLSxROWS, e.g. 9x6");
  if (live == !images_dir.empty())
    throw ParamError("command line", "", "", "give exactly one of --images DIR and --live");
  if (name.empty()) name = std::filesystem::path(output).stem().string();

  std::vector<cv::Mat> images;
  std::vector<std::string> names;
  if (live) {
    if (args.config.empty()) throw ParamError("command line", "", "", "--live needs --config");
    const int r = capture_live(load_params(args.config), board, views, interval_s, images, names);
    if (r != 0) return r;
  } else {
    names = image_files(images_dir);
    if (names.empty()) {
      spdlog::error("alight-calibrate: {}: no image files", images_dir);
      return 1;
    }
    for (const auto& f : names) {
      images.push_back(cv::imread(f, cv::IMREAD_GRAYSCALE));
      if (images.back().empty()) {
        spdlog::error("alight-calibrate: {}: not a readable image", f);
        return 1;
      }
    }
  }
  std::string err;
  const auto result = calibrate_chessboard(images, names, board, name, &err);
  if (!result) {
    spdlog::error("alight-calibrate: {}", err);
    return 1;
  }
  for (const auto& v : result->views) {
    if (v.found) {
      std::printf("%-40s rms %.3f px\n", v.name.c_str(), v.rms_px);
    } else {
      std::printf("%-40s no board found (not used)\n", v.name.c_str());
    }
  }
  const CameraModel& m = result->model;
  std::printf(
      "views used: %d of %zu\nRMS reprojection error: %.4f px\n"
      "fx %.3f fy %.3f cx %.3f cy %.3f  D [%.5f %.5f %.5f %.5f %.5f]\n",
      result->used_views, result->views.size(), result->rms_px, m.fx, m.fy, m.cx, m.cy, m.D[0],
      m.D[1], m.D[2], m.D[3], m.D[4]);
  save_camera_info(output, m);
  std::printf("wrote %s\n", output.c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return alight::run_node_main("alight-calibrate", [&] { return run(argc, argv); });
}
