#include "common/stamp_guard.hpp"

#include <algorithm>
#include <cmath>

namespace alight {

const char* stamp_verdict_name(StampVerdict v) {
  switch (v) {
    case StampVerdict::kAccepted:
      return "accepted";
    case StampVerdict::kRestarted:
      return "accepted as a restart of the source";
    case StampVerdict::kAdopted:
      return "accepted as the time base (the wall clock is far behind the inputs)";
    case StampVerdict::kNonPositive:
      return "stamp not positive";
    case StampVerdict::kBackwards:
      return "stamp older than the source's last";
    case StampVerdict::kAhead:
      return "stamp further ahead than can have elapsed";
  }
  return "?";
}

bool StampGuard::adopt(const std::string& source, int64_t utime, int64_t steady_us) {
  // A flood of source names must not grow memory: start over.
  if (candidates_.size() >= kMaxSources && !candidates_.count(source)) candidates_.clear();
  auto [it, fresh] = candidates_.try_emplace(source);
  Candidate& c = it->second;
  // Steady: never backwards, and never further ahead than the steady clock allows since the
  // source's last stamp (the same bound as for an accepted source). Otherwise start again.
  const double elapsed_us = static_cast<double>(std::max<int64_t>(0, steady_us - c.last_steady_us));
  const bool in_step = !fresh && utime >= c.last_utime &&
                       static_cast<double>(utime - c.last_utime) <=
                           params_.max_rate * elapsed_us + params_.tolerance_s * 1e6;
  if (!in_step) c = Candidate{utime, steady_us, utime, steady_us};
  c.last_utime = utime;
  c.last_steady_us = steady_us;
  return steady_us - c.first_steady_us >= static_cast<int64_t>(params_.adopt_after_s * 1e6) &&
         utime > c.first_utime;
}

int64_t StampGuard::reach_us(const Source& s, int64_t steady_us) const {
  const double elapsed_us = static_cast<double>(std::max<int64_t>(0, steady_us - s.last_steady_us));
  const double reach =
      static_cast<double>(s.last_utime) + params_.max_rate * elapsed_us + params_.tolerance_s * 1e6;
  return reach >= 9.2e18 ? INT64_MAX : static_cast<int64_t>(reach);
}

StampVerdict StampGuard::check(const std::string& source, int64_t utime, int64_t steady_us,
                               int64_t wall_us) {
  if (utime <= 0) return StampVerdict::kNonPositive;
  const auto it = sources_.find(source);
  StampVerdict verdict = StampVerdict::kAccepted;
  if (it == sources_.end()) {
    // First stamp of this source: against the others, else against the wall clock.
    int64_t bound = 0;
    bool any = false;
    for (const auto& [name, s] : sources_) {
      bound = any ? std::max(bound, reach_us(s, steady_us)) : reach_us(s, steady_us);
      any = true;
    }
    if (!any) bound = wall_us + static_cast<int64_t>(params_.max_first_ahead_s * 1e6);
    if (utime > bound) {
      if (any || !adopt(source, utime, steady_us)) return StampVerdict::kAhead;
      verdict = StampVerdict::kAdopted;
      inputs_time_base_ = true;
      candidates_.clear();
    }
  } else {
    Source& s = it->second;
    if (utime < s.last_utime) {
      if (steady_us - s.last_steady_us < static_cast<int64_t>(params_.reset_after_s * 1e6))
        return StampVerdict::kBackwards;
      verdict = StampVerdict::kRestarted;
    } else if (utime > reach_us(s, steady_us)) {
      return StampVerdict::kAhead;
    }
  }
  if (it == sources_.end() && sources_.size() >= kMaxSources) {
    // Publishers come and go (each start has a new id): forget the one silent the longest.
    auto oldest = sources_.begin();
    for (auto o = sources_.begin(); o != sources_.end(); ++o)
      if (o->second.last_steady_us < oldest->second.last_steady_us) oldest = o;
    sources_.erase(oldest);
  }
  Source& s = sources_[source];
  s.last_utime = utime;
  s.last_steady_us = steady_us;
  if (verdict == StampVerdict::kRestarted) {
    newest_utime_ = 0;
    for (const auto& [name, other] : sources_)
      newest_utime_ = std::max(newest_utime_, other.last_utime);
  } else {
    newest_utime_ = std::max(newest_utime_, utime);
  }
  return verdict;
}

}  // namespace alight
