#include "tools/seed_split.hpp"

#include <gtest/gtest.h>

#include "common/build_paths.hpp"

namespace alight::tools {
namespace {

SeedSplit split_of(const std::string& yaml) {
  return SeedSplit::from(ParamNode::from_string(yaml, "seeds.yaml"));
}

const char* kSplit = "tune: {first: 0, last: 999}\nreport: {first: 1000, last: 9999}\n";

TEST(SeedSplitTest, TheShippedSplitLoads) {
  const auto s = SeedSplit::from(
      ParamNode::load_file(std::string(alight::build::source_dir()) + "/config/seeds.yaml"));
  EXPECT_LT(s.tune.last, s.report.first);
}

TEST(SeedSplitTest, OverlappingRangesAreRefusedNamingTheFileAndKey) {
  try {
    split_of("tune: {first: 0, last: 1000}\nreport: {first: 1000, last: 2000}\n");
    FAIL() << "an overlap was accepted";
  } catch (const ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("seeds.yaml"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("report"), std::string::npos) << e.what();
  }
  EXPECT_THROW(split_of("tune: {first: 5, last: 4}\nreport: {first: 10, last: 20}\n"), ParamError);
  EXPECT_THROW(split_of("tune: {first: 0, last: 4}\nreport: {first: 10, last: 20}\nx: 1\n"),
               ParamError);
}

TEST(SeedSplitTest, TuningOnReportSeedsIsRefused) {
  const auto s = split_of(kSplit);
  EXPECT_EQ(check_seeds(s, SeedPurpose::kTune, 0, 19), "");
  EXPECT_NE(check_seeds(s, SeedPurpose::kTune, 990, 1009), "");
  EXPECT_NE(check_seeds(s, SeedPurpose::kTune, 5000, 5019), "");
}

TEST(SeedSplitTest, AReportFliesReportSeedsOnly) {
  const auto s = split_of(kSplit);
  EXPECT_EQ(check_seeds(s, SeedPurpose::kReport, 1000, 1019), "");
  EXPECT_NE(check_seeds(s, SeedPurpose::kReport, 990, 1009), "");
  EXPECT_NE(check_seeds(s, SeedPurpose::kReport, 0, 19), "");
  EXPECT_NE(check_seeds(s, SeedPurpose::kReport, 9990, 10009), "");  // past the range
  EXPECT_EQ(check_seeds(s, SeedPurpose::kAny, 0, 20000), "");
}

TEST(SeedSplitTest, TheSummaryNamesWhatTheSeedsAre) {
  const auto s = split_of(kSplit);
  EXPECT_EQ(describe_seeds(s, 0, 19), "tuning seeds");
  EXPECT_EQ(describe_seeds(s, 1000, 1019), "report seeds (fresh draws)");
  EXPECT_EQ(describe_seeds(s, 990, 1009), "seeds on both sides of the split");
  EXPECT_EQ(describe_seeds(s, 20000, 20019), "seeds outside the split");
}

TEST(SeedSplitTest, AFreshBlockLiesWithinTheReportRange) {
  const auto s = split_of(kSplit);
  for (uint64_t r : {uint64_t{0}, uint64_t{1}, uint64_t{123456789}, ~uint64_t{0}}) {
    const int64_t first = fresh_report_seed0(s, 20, r);
    EXPECT_EQ(check_seeds(s, SeedPurpose::kReport, first, first + 19), "") << r;
  }
  EXPECT_EQ(parse_seed_purpose("report"), SeedPurpose::kReport);
  EXPECT_THROW(parse_seed_purpose("fresh"), std::invalid_argument);
}

}  // namespace
}  // namespace alight::tools
