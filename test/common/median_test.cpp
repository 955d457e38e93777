#include "common/median.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

namespace alight {
namespace {

TEST(UpperMedianTest, TheMiddleOfAnOddCountAndTheLargerMiddleOfAnEvenOne) {
  EXPECT_EQ(upper_median(std::vector<double>{3.0}), 3.0);
  EXPECT_EQ(upper_median(std::vector<double>{5.0, -1.0, 2.0}), 2.0);
  EXPECT_EQ(upper_median(std::vector<double>{4.0, 1.0, 3.0, 2.0}), 3.0);
  EXPECT_EQ(upper_median(std::vector<uint8_t>{9, 200, 7, 7}), 9);
}

TEST(UpperMedianTest, AMinorityOfOutliersDoesNotMoveIt) {
  std::vector<double> v = {1.0, 1.1, 0.9, 1.05, 0.95, 1e9, -1e9};
  EXPECT_EQ(upper_median(v), 1.0);
  v.push_back(1e12);
  EXPECT_EQ(upper_median(v), 1.05);
}

TEST(UpperMedianTest, TheCallersSampleIsLeftAsItWas) {
  const std::vector<double> v = {3.0, 1.0, 2.0};
  EXPECT_EQ(upper_median(v), 2.0);
  EXPECT_EQ(v, (std::vector<double>{3.0, 1.0, 2.0}));
}

}  // namespace
}  // namespace alight
