// The outer loop's state file: round trip, atomic replacement, corrupt files, trusted ages.

#include "outer_loop/state_file.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "common/build_paths.hpp"

namespace alight::outer_loop {
namespace {

std::filesystem::path temp_dir() {
  const auto d = std::filesystem::path(alight::build::binary_dir()) / "test_tmp" /
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
  ASSERT_TRUE(save_state(path, {{true, false}, 123, "", 0}, &error)) << error;
  ASSERT_TRUE(save_state(path, {{true, true}, 456, "", 0}, &error)) << error;
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
  const std::string good = format_state({{true, true}, 42, "", 0});
  ASSERT_TRUE(parse_state(good));
  for (size_t n = 0; n < good.size() - 1; ++n) EXPECT_FALSE(parse_state(good.substr(0, n))) << n;
  std::string bad = good;
  bad.replace(bad.find("armed 1"), 7, "armed 7");
  EXPECT_FALSE(parse_state(bad));
  EXPECT_FALSE(parse_state("garbage"));
}

TEST(OuterLoopStateFileTest, ALatchIsAlwaysRestoredArmedOnlyFromARecentRecord) {
  const int64_t now = 1'700'000'000'000'000;
  const RestoreClock clock{now, "another-boot", 0};
  EXPECT_FALSE(restored_state(std::nullopt, clock, 10).disarm_latched);
  auto s = restored_state(StateRecord{{true, true}, now - 5'000'000, "", 0}, clock, 10);
  EXPECT_TRUE(s.disarm_latched);
  EXPECT_TRUE(s.armed);
  s = restored_state(StateRecord{{true, true}, now - 3'600'000'000LL, "", 0}, clock, 10);
  EXPECT_TRUE(s.disarm_latched) << "a latch never expires";
  EXPECT_FALSE(s.armed) << "an old session's 'armed' is not trusted";
}

// A companion without a real-time clock: the outer loop restarted in flight with its wall clock
// at 1970 still knows the record is a second old (same boot: the steady clock ran on), and a
// record from an earlier boot is judged on the wall clock.
TEST(OuterLoopStateFileTest, WithinOneBootTheRecordIsAgedOnTheSteadyClock) {
  const int64_t written_wall = 1'800'000'000'000'000, written_steady = 5'000'000'000;
  const StateRecord r{{false, true}, written_wall, "boot-a", written_steady};
  const RestoreClock no_rtc{86'400'000'000, "boot-a", written_steady + 1'000'000};
  EXPECT_TRUE(restored_state(r, no_rtc, 10).armed);
  const RestoreClock later_same_boot{86'400'000'000, "boot-a", written_steady + 60'000'000};
  EXPECT_FALSE(restored_state(r, later_same_boot, 10).armed);
  const RestoreClock other_boot{written_wall + 1'000'000, "boot-b", 1'000'000};
  EXPECT_TRUE(restored_state(r, other_boot, 10).armed);
  const RestoreClock other_boot_no_rtc{86'400'000'000, "boot-b", 1'000'000};
  EXPECT_FALSE(restored_state(r, other_boot_no_rtc, 10).armed);
  const auto back = parse_state(format_state(r));
  ASSERT_TRUE(back);
  EXPECT_EQ(back->boot_id, "boot-a");
  EXPECT_EQ(back->steady_utime, written_steady);
}

}  // namespace
}  // namespace alight::outer_loop
