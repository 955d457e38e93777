// The node logs a reason when what it says changes, not its numbers (autonomy/text.hpp).

#include "autonomy/text.hpp"

#include <gtest/gtest.h>

namespace alight::autonomy {
namespace {

TEST(ReasonKind, NumbersBecomeOneMarkEachAndTheWordsStay) {
  EXPECT_EQ(reason_kind("matching the moving platform (0.03 m, 0.01 m/s off)"),
            "matching the moving platform (# m, # m/s off)");
  EXPECT_EQ(reason_kind("matching the moving platform (0.04 m, 0.12 m/s off)"),
            reason_kind("matching the moving platform (0.03 m, 0.01 m/s off)"));
  EXPECT_EQ(reason_kind("e_r -1.5e-3, retry 2 of 3"), "e_r #e#, retry # of #");
  EXPECT_EQ(reason_kind("FINAL_DESCENT: moving platform matched, final descent (no heave)"),
            "FINAL_DESCENT: moving platform matched, final descent (no heave)");
  EXPECT_NE(reason_kind("searching"), reason_kind("holding"));
  EXPECT_EQ(reason_kind(""), "");
  EXPECT_EQ(reason_kind("a - b."), "a - b.");  // a sign or a point with no digit after it
}

}  // namespace
}  // namespace alight::autonomy
