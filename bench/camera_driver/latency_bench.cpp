// End-to-end latency of alight-camera with a video file source: from the frame's buffer
// timestamp (image_t.utime, taken before the frame is decoded) to the CAMERA message received
// and decoded by a subscriber over LCM on this machine.
//
//   build/bin/camera_latency_bench [--frames N] [--fps F] [--rgb]
//
// Writes a 640x480 MJPEG AVI (OpenCV's built-in writer) to a temporary folder, starts
// alight-camera --source file:... at the file's rate, and reports median, p99 and max [ms].

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <alight/image_t.hpp>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>
#include <random>
#include <string>
#include <vector>

#include "common/build_paths.hpp"
#include "common/image_msg.hpp"
#include "common/node.hpp"

namespace {
const std::string kUrl = "udpm://239.255.76.67:7792?ttl=0";

double percentile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  const size_t i = std::min(v.size() - 1, static_cast<size_t>(q * (v.size() - 1) + 0.5));
  return v[i];
}
}  // namespace

int main(int argc, char** argv) {
  int frames = 300;
  double fps = 30.0;
  bool rgb = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--frames" && i + 1 < argc)
      frames = std::stoi(argv[++i]);
    else if (a == "--fps" && i + 1 < argc)
      fps = std::stod(argv[++i]);
    else if (a == "--rgb")
      rgb = true;
    else {
      std::fprintf(stderr, "usage: %s [--frames N] [--fps F] [--rgb]\n", argv[0]);
      return 2;
    }
  }
  namespace fs = std::filesystem;
  const fs::path dir =
      fs::temp_directory_path() / ("alight_camera_latency_" + std::to_string(getpid()));
  fs::create_directories(dir);
  const std::string video = (dir / "clip.avi").string();
  {
    cv::VideoWriter w(video, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), fps, cv::Size(640, 480));
    if (!w.isOpened()) {
      std::fprintf(stderr, "cannot write %s\n", video.c_str());
      return 1;
    }
    std::mt19937_64 rng(3);
    cv::Mat img(480, 640, CV_8UC3);
    for (int i = 0; i < frames; ++i) {
      cv::randu(img, cv::Scalar::all(60), cv::Scalar::all(200));
      cv::GaussianBlur(img, img, cv::Size(9, 9), 3);
      cv::putText(img, std::to_string(i), cv::Point(200, 260), cv::FONT_HERSHEY_SIMPLEX, 4,
                  cv::Scalar(255, 255, 255), 8);
      w.write(img);
    }
  }
  const std::string cfg = (dir / "cam.yaml").string();
  std::ofstream(cfg) << "channel: CAMERA_LATENCY\noutput_encoding: " << (rgb ? "rgb8" : "mono8")
                     << "\ncamera_info: " << alight::build::source_dir()
                     << "/config/cameras/firefly_mv_4mm.yaml\n";

  alight::Node rx(kUrl, "camera_latency_bench");
  std::vector<double> latency_ms;
  int64_t last_seq = -1, gaps = 0;
  rx.on<alight::image_t>("CAMERA_LATENCY", [&](const alight::image_t& m) {
    std::string err;
    const auto img = alight::image_from_msg(m, !rgb, &err);  // a consumer decodes it
    const int64_t now = alight::wall_utime();
    if (!img) return;
    latency_ms.push_back((now - m.utime) / 1000.0);
    const int64_t seq = alight::metadata_int(m, "seq").value_or(-1);
    if (last_seq >= 0 && seq != last_seq + 1) ++gaps;
    last_seq = seq;
  });
  const std::string cmd = std::string(alight::build::binary_dir()) +
                          "/bin/alight-camera --config " + cfg + " --lcm-url '" + kUrl +
                          "' --source file:" + video + " --log-level warn";
  const pid_t pid = fork();
  if (pid == 0) {
    execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  int status = 0;
  const auto deadline =
      std::chrono::steady_clock::now() +
      std::chrono::milliseconds(static_cast<int64_t>(frames / fps * 1000) + 10000);
  while (std::chrono::steady_clock::now() < deadline) {
    rx.spin_once(20);
    if (waitpid(pid, &status, WNOHANG) == pid) {
      for (int i = 0; i < 10; ++i) rx.spin_once(20);  // the last messages in flight
      break;
    }
  }
  fs::remove_all(dir);
  if (latency_ms.empty()) {
    std::fprintf(stderr, "no CAMERA message received (alight-camera exit status %d)\n", status);
    return 1;
  }
  double mean = 0;
  for (double l : latency_ms) mean += l;
  mean /= latency_ms.size();
  std::printf("alight-camera file source, 640x480 MJPEG AVI at %.0f fps -> %s CAMERA over LCM\n",
              fps, rgb ? "rgb8" : "mono8");
  std::printf("frames received %zu of %d, sequence gaps %ld\n", latency_ms.size(), frames,
              static_cast<long>(gaps));
  std::printf(
      "latency buffer timestamp -> received+decoded [ms]: median %.3f  p99 %.3f  "
      "max %.3f  mean %.3f\n",
      percentile(latency_ms, 0.5), percentile(latency_ms, 0.99),
      *std::max_element(latency_ms.begin(), latency_ms.end()), mean);
  return 0;
}
