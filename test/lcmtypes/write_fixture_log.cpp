// Writes a small session log with LCM's own log writer: one message of several alight types on
// their usual channels, for the Java and Python readers' tests.
#include <alight/autonomy_status_t.hpp>
#include <alight/pose_t.hpp>
#include <alight/process_status_t.hpp>
#include <alight/target_t.hpp>
#include <cstdio>
#include <lcm/lcm-cpp.hpp>
#include <opencv2/core.hpp>

#include "common/channels.hpp"
#include "common/image_msg.hpp"
#include "common/msg_convert.hpp"

namespace {
template <class T>
void write(lcm::LogFile& log, int64_t utime, const char* channel, const T& msg) {
  std::vector<uint8_t> buf(msg.getEncodedSize());
  msg.encode(buf.data(), 0, static_cast<int>(buf.size()));
  lcm::LogEvent ev;
  ev.eventnum = 0;
  ev.timestamp = utime;
  ev.channel = channel;
  ev.datalen = static_cast<int32_t>(buf.size());
  ev.data = buf.data();
  log.writeEvent(&ev);
}
}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: write_fixture_log OUT.lcmlog\n");
    return 2;
  }
  lcm::LogFile log(argv[1], "w");
  if (!log.good()) {
    std::fprintf(stderr, "cannot write %s\n", argv[1]);
    return 1;
  }
  const int64_t t0 = 1'790'000'000'000'000;
  for (int i = 0; i < 10; ++i) {
    alight::PoseSample s;
    s.utime = t0 + i * 10'000;
    s.p_W_B = Eigen::Vector3d(0.1 * i, 0, 1.5);
    write(log, s.utime, alight::channels::kMocapPose, alight::to_msg(s, i));
  }
  write(log, t0 + 50'000, alight::channels::kCamera,
        alight::image_to_msg(cv::Mat(480, 640, CV_8UC1, cv::Scalar(128)), t0 + 50'000, 0));
  alight::target_t t{};
  t.utime = t0 + 50'000;
  t.found = true;
  t.mission = alight::target_t::MISSION_LANDING;
  t.p_W_target[0] = 1.25;
  write(log, t0 + 90'000, alight::channels::kVisionTarget, t);
  alight::autonomy_status_t st{};
  st.utime = t0 + 95'000;
  st.phase_name = "REFINEMENT";
  write(log, t0 + 95'000, alight::channels::kAutonomyStatus, st);
  alight::process_status_t ps{};
  ps.utime = t0 + 99'000;
  ps.launch_name = "fixture";
  ps.n = 0;
  write(log, t0 + 99'000, alight::channels::kProcessStatus, ps);
  return 0;
}
