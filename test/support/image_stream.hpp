#pragma once
// Streams 640x480 mono8 CAMERA-like images from a forked publisher process to this process over
// LCM and counts what arrives by sequence number, with publish -> receive latency. Shared by
// the transport test (test/integration) and the transport benchmark (bench/lcm).
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <alight/image_t.hpp>
#include <chrono>
#include <cmath>
#include <lcm/lcm-cpp.hpp>
#include <opencv2/core.hpp>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "common/image_msg.hpp"
#include "common/node.hpp"

namespace alight::testing {

struct StreamResult {
  int sent = 0;
  int received = 0;  ///< distinct sequence numbers received
  int duplicates = 0;
  std::vector<double> latency_ms;  ///< per received image, publish -> callback
  int lost() const { return sent - received; }
  double percentile_ms(double q) const {
    if (latency_ms.empty()) return NAN;
    std::vector<double> v = latency_ms;
    const size_t k = std::min(v.size() - 1, static_cast<size_t>(q * static_cast<double>(v.size())));
    std::nth_element(v.begin(), v.begin() + k, v.end());
    return v[k];
  }
};

/// How the receiving side is set up: alight's Node (large receive buffer, deep queue), or
/// LCM 1.3.1 as it comes on Debian (the kernel's default 208 KiB socket buffer, asked for
/// explicitly so a raised rmem_default does not hide it, and the 30-message queue).
enum class Receiver { kAlightNode, kPlainLcm };
inline constexpr int kStockRecvBufBytes = 212992;  // Debian's net.core.rmem_default

namespace detail {
inline void publish_stream(const std::string& url, const std::string& channel, double fps,
                           int count) {
  lcm::LCM lcm(with_receive_buffer(url));
  cv::Mat pixels(480, 640, CV_8UC1);
  cv::randu(pixels, 0, 255);  // incompressible, as camera noise is
  image_t msg = image_to_msg(pixels, 0, 0);
  const auto period = std::chrono::duration<double>(fps > 0 ? 1.0 / fps : 0.0);
  auto next = std::chrono::steady_clock::now();
  for (int i = 0; i < count; ++i) {
    if (fps > 0) {
      std::this_thread::sleep_until(next);
      next += std::chrono::duration_cast<std::chrono::steady_clock::duration>(period);
    }
    set_metadata_int(msg, "seq", i);
    msg.utime = wall_utime();
    lcm.publish(channel, &msg);
  }
}

struct PlainHandler {
  StreamResult* r;
  std::set<int64_t>* seen;
  int64_t* last_utime;
  void on(const lcm::ReceiveBuffer* rbuf, const std::string&, const image_t* m) {
    const int64_t now = wall_utime();
    const auto seq = metadata_int(*m, "seq").value_or(-1);
    if (!seen->insert(seq).second) ++r->duplicates;
    r->latency_ms.push_back(1e-3 * static_cast<double>(now - m->utime));
    *last_utime = now;
    (void)rbuf;
  }
};
}  // namespace detail

/// Publishes `count` images at `fps` (<= 0: as fast as possible) from a child process and
/// receives them here. Ends `settle_s` after the last image arrived or the publisher finished.
inline StreamResult run_image_stream(const std::string& url, const std::string& channel, double fps,
                                     int count, Receiver receiver, double settle_s = 0.5) {
  StreamResult r;
  r.sent = count;
  std::set<int64_t> seen;
  int64_t last_utime = wall_utime();
  std::unique_ptr<Node> node;
  std::unique_ptr<lcm::LCM> plain;
  detail::PlainHandler handler{&r, &seen, &last_utime};
  if (receiver == Receiver::kAlightNode) {
    node = std::make_unique<Node>(url, "stream-rx");
    node->on<image_t>(channel, [&](const image_t& m) {
      const int64_t now = wall_utime();
      if (!seen.insert(metadata_int(m, "seq").value_or(-1)).second) ++r.duplicates;
      r.latency_ms.push_back(1e-3 * static_cast<double>(now - m.utime));
      last_utime = now;
    });
  } else {
    plain = std::make_unique<lcm::LCM>(with_receive_buffer(url, kStockRecvBufBytes));
    plain->subscribe(channel, &detail::PlainHandler::on, &handler);
  }
  const pid_t child = fork();
  if (child == 0) {
    std::this_thread::sleep_for(std::chrono::milliseconds(300));  // receiver is subscribed
    detail::publish_stream(url, channel, fps, count);
    _exit(0);
  }
  bool publisher_done = false;
  int64_t done_utime = 0;
  while (true) {
    if (node) {
      node->spin_once(20);
    } else {
      plain->handleTimeout(20);
    }
    if (!publisher_done && waitpid(child, nullptr, WNOHANG) == child) {
      publisher_done = true;
      done_utime = wall_utime();
    }
    const int64_t now = wall_utime();
    if (publisher_done && static_cast<int>(seen.size()) >= count) break;
    if (publisher_done && now - std::max(done_utime, last_utime) > settle_s * 1e6) break;
  }
  r.received = static_cast<int>(seen.size());
  return r;
}

}  // namespace alight::testing
