// The outer loop's state file: round trip, atomic replacement, corrupt files, trusted ages.

#include "outer_loop/state_file.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

namespace alight::outer_loop {
namespace {

std::filesystem::path temp_dir() {
  const auto d = std::filesystem::path(ALIGHT_BINARY_DIR) / "test_tmp" /
                 (std::string("outer_loop_state_") +
                  ::testing::UnitTest::GetInstance()->current_test_info()->name());
  std::filesystem::remove_all(d);
  return d;
}

TEST(OuterLoopStateFileTest, RoundTripsAndReplacesAtomically) {
  const auto dir = temp_dir();
  const std::string path = (dir / "sub" / "outer_loop.state").string();
  std::string error;
  EXPECT_FALSE(load_state(path, &error));
  EXPECT_TRUE(error.empty()) << "absent is not an error";
  ASSERT_TRUE(save_state(path, {{true, false}, 123}, &error)) << error;
  ASSERT_TRUE(save_state(path, {{true, true}, 456}, &error)) << error;
  const auto r = load_state(path, &error);
  ASSERT_TRUE(r);
  EXPECT_TRUE(r->state.disarm_latched);
  EXPECT_TRUE(r->state.armed);
  EXPECT_EQ(r->wall_utime, 456);
  int files = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir / "sub")) {
    ++files;
    EXPECT_EQ(e.path().filename(), "outer_loop.state") << "no temporary left";
  }
  EXPECT_EQ(files, 1);
}

TEST(OuterLoopStateFileTest, CorruptOrTruncatedFilesAreRefused) {
  const std::string good = format_state({{true, true}, 42});
  ASSERT_TRUE(parse_state(good));
  for (size_t n = 0; n < good.size() - 1; ++n) EXPECT_FALSE(parse_state(good.substr(0, n))) << n;
  std::string bad = good;
  bad.replace(bad.find("armed 1"), 7, "armed 7");
  EXPECT_FALSE(parse_state(bad));
  EXPECT_FALSE(parse_state("garbage"));
}

TEST(OuterLoopStateFileTest, ALatchIsAlwaysRestoredArmedOnlyFromARecentRecord) {
  const int64_t now = 1'700'000'000'000'000;
  EXPECT_FALSE(restored_state(std::nullopt, now, 10).disarm_latched);
  auto s = restored_state(StateRecord{{true, true}, now - 5'000'000}, now, 10);
  EXPECT_TRUE(s.disarm_latched);
  EXPECT_TRUE(s.armed);
  s = restored_state(StateRecord{{true, true}, now - 3'600'000'000LL}, now, 10);
  EXPECT_TRUE(s.disarm_latched) << "a latch never expires";
  EXPECT_FALSE(s.armed) << "an old session's 'armed' is not trusted";
}

}  // namespace
}  // namespace alight::outer_loop
