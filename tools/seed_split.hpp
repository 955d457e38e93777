#pragma once
// The split of scene seeds between tuning and reporting (config/seeds.yaml,
// docs/results.md#seeds). A figure that claims scenes nobody tuned to is worth something only if
// no change was tuned on those scenes; the Monte Carlo tools check a run's seeds against the
// split so that a report on tuning seeds, or tuning on report seeds, is refused instead of
// trusted.

#include <cstdint>
#include <string>

#include "common/params.hpp"

namespace alight::tools {

struct SeedRange {
  int64_t first = 0, last = 0;  ///< inclusive
  bool contains(int64_t s) const { return s >= first && s <= last; }
  bool overlaps(int64_t a, int64_t b) const { return a <= last && b >= first; }
};

struct SeedSplit {
  SeedRange tune, report;
  /// Reads `tune: {first, last}` and `report: {first, last}`; throws ParamError naming the file
  /// and key when a range is empty, negative, or the two overlap.
  static SeedSplit from(const ParamNode& node);
};

enum class SeedPurpose { kAny, kTune, kReport };

/// Parses "any" | "tune" | "report"; throws std::invalid_argument otherwise.
SeedPurpose parse_seed_purpose(const std::string& text);

/// What the seeds first..last are to the split: "tuning seeds", "report seeds (fresh draws)",
/// or "seeds outside the split" / "seeds on both sides of the split".
std::string describe_seeds(const SeedSplit& split, int64_t first, int64_t last);

/// Empty when seeds first..last may serve `purpose`; otherwise why not (tuning on any report
/// seed, or reporting on any seed that is not a report seed).
std::string check_seeds(const SeedSplit& split, SeedPurpose purpose, int64_t first, int64_t last);

/// The first seed of a fresh block of `n` report seeds, from a random number `r`.
int64_t fresh_report_seed0(const SeedSplit& split, int64_t n, uint64_t r);

}  // namespace alight::tools
