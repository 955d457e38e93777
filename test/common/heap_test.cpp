// retain_freed_memory (common/heap.hpp): a frame-sized buffer allocated, written and freed again
// and again costs page faults only the first time.
#include "common/heap.hpp"

#include <gtest/gtest.h>
#include <sys/resource.h>

#include <cstring>
#include <memory>

namespace alight {
namespace {

long minor_faults() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_minflt;
}

/// Minor page faults of n frames, each allocating, writing and freeing four 640x480 float
/// buffers (a frame's integral image, STAR response and dilated response, a copy).
long faults_of_frames(int n) {
  const size_t bytes = 640 * 480 * sizeof(float);
  const long before = minor_faults();
  for (int i = 0; i < n; ++i) {
    std::unique_ptr<char[]> buf[4];
    for (auto& b : buf) {
      b.reset(new char[bytes]);
      std::memset(b.get(), i, bytes);
      asm volatile("" : : "r"(b.get()) : "memory");  // the writes are not optimised away
    }
  }
  return minor_faults() - before;
}

TEST(HeapTest, RetainedMemoryIsReusedWithoutPageFaultsFrameAfterFrame) {
  // glibc's default: a buffer above 128 KiB is mapped and unmapped each time (or the dynamic
  // threshold moves and the trimmed heap top faults in again).
  ASSERT_TRUE(retain_freed_memory());
  faults_of_frames(1);  // the first frame grows the heap
  const long faults = faults_of_frames(50);
  // Under glibc's defaults the four buffers' 4.7 MB go back to the kernel after every frame
  // (58000 faults in 50 frames here).
  EXPECT_LT(faults, 300) << faults << " minor page faults in 50 frames";
}

}  // namespace
}  // namespace alight
