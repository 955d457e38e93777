// Two processes over UDP multicast on loopback: 640x480 mono images at 30 fps for 10 s arrive
// with no loss (counted by sequence number) through alight's node helper.
#include <gtest/gtest.h>

#include "support/image_stream.hpp"

namespace alight {
namespace {

TEST(ImageTransportTest, ThirtyFpsForTenSecondsArrivesWithoutLoss) {
  const auto r = testing::run_image_stream("udpm://239.255.76.67:7714?ttl=0", "CAMERA_TEST", 30.0,
                                           300, testing::Receiver::kAlightNode);
  EXPECT_EQ(r.received, 300) << "lost " << r.lost();
  EXPECT_EQ(r.duplicates, 0);
  // Loopback, one frame every 33 ms: a frame that needs a whole frame time is a fault.
  EXPECT_LT(r.percentile_ms(0.5), 33.0);
}

}  // namespace
}  // namespace alight
