#include "tools/seed_split.hpp"

#include <stdexcept>

namespace alight::tools {
namespace {

SeedRange read_range(const ParamNode& parent, const std::string& key) {
  const ParamNode n = parent.child(key);
  SeedRange r;
  n.require("first", r.first);
  n.require("last", r.last);
  n.check(r.first >= 0, "first", "must be >= 0");
  n.check(r.last >= r.first, "last", "must be >= first");
  n.finish();
  return r;
}

}  // namespace

SeedSplit SeedSplit::from(const ParamNode& node) {
  SeedSplit s;
  s.tune = read_range(node, "tune");
  s.report = read_range(node, "report");
  node.check(!s.tune.overlaps(s.report.first, s.report.last), "report",
             "overlaps the tune range: a seed is either tuned on or reported on, not both");
  node.finish();
  return s;
}

SeedPurpose parse_seed_purpose(const std::string& text) {
  if (text == "any") return SeedPurpose::kAny;
  if (text == "tune") return SeedPurpose::kTune;
  if (text == "report") return SeedPurpose::kReport;
  throw std::invalid_argument("purpose must be any, tune or report, not '" + text + "'");
}

std::string describe_seeds(const SeedSplit& split, int64_t first, int64_t last) {
  const bool all_tune = split.tune.contains(first) && split.tune.contains(last);
  const bool all_report = split.report.contains(first) && split.report.contains(last);
  if (all_tune) return "tuning seeds";
  if (all_report) return "report seeds (fresh draws)";
  if (split.tune.overlaps(first, last) || split.report.overlaps(first, last))
    return "seeds on both sides of the split";
  return "seeds outside the split";
}

std::string check_seeds(const SeedSplit& split, SeedPurpose purpose, int64_t first, int64_t last) {
  const std::string range = std::to_string(first) + ".." + std::to_string(last);
  if (purpose == SeedPurpose::kTune && split.report.overlaps(first, last))
    return "seeds " + range + " include report seeds (" + std::to_string(split.report.first) +
           ".." + std::to_string(split.report.last) + "): tuning on them spends them";
  if (purpose == SeedPurpose::kReport &&
      !(split.report.contains(first) && split.report.contains(last)))
    return "seeds " + range + " are not all report seeds (" + std::to_string(split.report.first) +
           ".." + std::to_string(split.report.last) + "): a report flies fresh draws only";
  return {};
}

int64_t fresh_report_seed0(const SeedSplit& split, int64_t n, uint64_t r) {
  const int64_t span = split.report.last - split.report.first + 1 - n;
  if (span <= 0) return split.report.first;
  return split.report.first + static_cast<int64_t>(r % static_cast<uint64_t>(span));
}

}  // namespace alight::tools
