// Image transport over LCM UDP multicast on loopback, two processes, 640x480 mono8 (307 KB):
//  1. latency publish -> receive, median and p99, at 30 and 60 fps;
//  2. the highest sustained rate with zero loss (rates doubled until images are lost, then
//     bisected), for alight's Node side by side with LCM 1.3.1 as it comes (default socket
//     buffer, 30-message queue).
// Usage: bench_lcm_images [--seconds S] [--url URL]
#include <cstdio>
#include <cstring>
#include <string>

#include "support/image_stream.hpp"

using alight::testing::Receiver;
using alight::testing::run_image_stream;

namespace {
const char* name(Receiver r) {
  return r == Receiver::kAlightNode ? "alight Node" : "plain LCM 1.3.1";
}

bool lossless(const std::string& url, double fps, double seconds, Receiver rx) {
  const auto r = run_image_stream(url, "BENCH_IMAGES", fps, static_cast<int>(fps * seconds), rx);
  std::printf("    %-16s %7.0f fps: sent %6d lost %5d  latency median %6.2f ms p99 %7.2f ms\n",
              name(rx), fps, r.sent, r.lost(), r.percentile_ms(0.5), r.percentile_ms(0.99));
  std::fflush(stdout);
  return r.lost() == 0;
}
}  // namespace

int main(int argc, char** argv) {
  double seconds = 5.0;
  std::string url = "udpm://239.255.76.67:7720?ttl=0";
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--seconds")) seconds = std::stod(argv[i + 1]);
    if (!std::strcmp(argv[i], "--url")) url = argv[i + 1];
  }
  std::printf("LCM image transport, 640x480 mono8, %s, %.0f s per point\n\n", url.c_str(), seconds);
  std::printf("Latency at camera rates:\n");
  for (Receiver rx : {Receiver::kAlightNode, Receiver::kPlainLcm})
    for (double fps : {30.0, 60.0}) lossless(url, fps, seconds, rx);

  std::printf("\nHighest sustained zero-loss rate:\n");
  for (Receiver rx : {Receiver::kAlightNode, Receiver::kPlainLcm}) {
    double good = 0, bad = 0;
    for (double fps = 30; fps <= 7680; fps *= 2) {
      if (lossless(url, fps, seconds, rx)) {
        good = fps;
      } else {
        bad = fps;
        break;
      }
    }
    if (bad > 0 && good > 0) {
      for (int i = 0; i < 4; ++i) {
        const double mid = 0.5 * (good + bad);
        (lossless(url, mid, seconds, rx) ? good : bad) = mid;
      }
    }
    std::printf("  => %s: %.0f fps with zero loss%s\n\n", name(rx), good,
                bad == 0 ? " (the highest rate tried)" : "");
  }
  return 0;
}
