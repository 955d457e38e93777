// The autonomy's state record across restarts (autonomy/restart_state.hpp): format and parse,
// the restore decision (same boot, same session, fresh heartbeat), and the file written by
// rename.

#include "autonomy/restart_state.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

namespace alight::autonomy {
namespace {

RestartRecord killed_record() {
  RestartRecord r;
  r.boot_id = "boot-a";
  r.session = 4242;
  r.steady_utime = 100'000'000;
  r.state.killed = true;
  r.state.failsafe = Failsafe::kKill;
  r.state.motors_on = false;
  return r;
}

TEST(RestartStateTest, RecordRoundTripsAndCorruptOnesAreRefused) {
  const RestartRecord r = killed_record();
  std::string why;
  const auto back = parse_record(format_record(r), &why);
  ASSERT_TRUE(back) << why;
  EXPECT_EQ(back->boot_id, r.boot_id);
  EXPECT_EQ(back->session, r.session);
  EXPECT_EQ(back->steady_utime, r.steady_utime);
  EXPECT_EQ(back->state, r.state);

  RestartRecord flying;
  flying.boot_id = "b";
  flying.state.motors_on = true;
  flying.state.failsafe = Failsafe::kPoseLost;
  EXPECT_EQ(parse_record(format_record(flying), &why)->state, flying.state);
  flying.state.failsafe = Failsafe::kEstimateLost;  // issue 17
  EXPECT_NE(format_record(flying).find("failsafe ESTIMATE_LOST"), std::string::npos);
  EXPECT_EQ(parse_record(format_record(flying), &why)->state, flying.state);

  const std::string text = format_record(r);
  EXPECT_FALSE(parse_record("", &why));
  EXPECT_FALSE(parse_record(text.substr(0, text.size() / 2), &why)) << "cut short";
  std::string bad = text;
  bad.replace(bad.find("killed 1"), 8, "killed 7");
  EXPECT_FALSE(parse_record(bad, &why));
  bad = text;
  bad.replace(bad.find("KILL"), 4, "BOOM");
  EXPECT_FALSE(parse_record(bad, &why));
}

TEST(RestartStateTest, RestoredOnlyInTheSameBootAndSessionWhileFresh) {
  const RestartRecord r = killed_record();
  std::string why;
  const int64_t now = r.steady_utime + 5'000'000;  // 5 s later
  EXPECT_TRUE(restore_state(r, "boot-a", 4242, now, 60.0, &why).killed) << why;
  EXPECT_FALSE(restore_state(r, "boot-b", 4242, now, 60.0, &why).killed) << "after a reboot";
  EXPECT_FALSE(restore_state(r, "boot-a", 999, now, 60.0, &why).killed) << "a new launch";
  EXPECT_NE(why.find("session"), std::string::npos) << why;
  EXPECT_FALSE(restore_state(r, "boot-a", 4242, r.steady_utime + 61'000'000, 60.0, &why).killed);
  EXPECT_FALSE(restore_state(r, "boot-a", 4242, r.steady_utime - 1, 60.0, &why).killed)
      << "a heartbeat from the future";
  EXPECT_FALSE(restore_state(std::nullopt, "boot-a", 4242, now, 60.0, &why).killed);
  EXPECT_FALSE(restore_state(r, "", 4242, now, 60.0, &why).killed) << "boot id unknown";
}

TEST(RestartStateTest, FileIsReplacedWholeAndReadBack) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("alight_restart_state_test_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  const std::string path = (dir / "autonomy.state").string();
  std::string why;
  EXPECT_FALSE(read_state_file(path, &why));
  ASSERT_TRUE(write_state_file(path, format_record(killed_record()), &why)) << why;
  EXPECT_EQ(std::filesystem::status(dir).permissions() & std::filesystem::perms::all,
            std::filesystem::perms::owner_all)
      << "the directory is private";
  RestartRecord second = killed_record();
  second.state.killed = false;
  ASSERT_TRUE(write_state_file(path, format_record(second), &why)) << why;
  const auto text = read_state_file(path, &why);
  ASSERT_TRUE(text) << why;
  const auto back = parse_record(*text, &why);
  ASSERT_TRUE(back) << why;
  EXPECT_FALSE(back->state.killed);
  EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));
  std::filesystem::remove_all(dir);

  EXPECT_NE(default_state_path("udpm://239.255.76.67:7667?ttl=0"),
            default_state_path("udpm://239.255.76.67:7947?ttl=0"))
      << "one file per LCM network";
  EXPECT_FALSE(read_boot_id().empty());
}

}  // namespace
}  // namespace alight::autonomy
