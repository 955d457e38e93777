#pragma once
// Mission progress for people watching a run (scripts/demo): phase changes, the measurement
// count and the estimate against the simulator's truth, one line at a time, and when the
// mission is over. Pure: fed messages, driven by their utime.

#include <alight/autonomy_status_t.hpp>
#include <alight/sim_truth_t.hpp>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace alight::tools {

struct MonitorParams {
  double timeout_s = 300.0;        ///< mission time after which the run counts as failed [s]
  double progress_period_s = 2.0;  ///< at most one progress line per this long [s]
  /// After autonomy reports LANDED, the simulator's verdict (at rest on the platform top, or
  /// tipped) is awaited this long in sim time; without SIM_TRUTH the autonomy's word stands [s].
  double settle_s = 3.0;
};

class MissionMonitor {
 public:
  enum class End { kNone, kSuccess, kFailure };

  explicit MissionMonitor(MonitorParams params = {}) : params_(params) {}

  /// Each returns the lines to print (possibly none).
  std::vector<std::string> add(const autonomy_status_t& status);
  std::vector<std::string> add(const sim_truth_t& truth);

  End end() const { return end_; }
  const std::string& end_reason() const { return end_reason_; }

 private:
  std::string stamp(int64_t utime) const;
  std::string estimate_text(const autonomy_status_t& s) const;
  void finish(End end, const std::string& reason, std::vector<std::string>& out);

  MonitorParams params_;
  std::optional<int64_t> t0_;
  std::optional<autonomy_status_t> last_;
  std::optional<sim_truth_t> truth_;
  std::optional<int64_t> landed_utime_;  // autonomy reported LANDED; the sim's verdict pending
  void check_landed(int64_t utime, std::vector<std::string>& out);
  int64_t last_progress_utime_ = 0;
  int last_count_ = 0;
  End end_ = End::kNone;
  std::string end_reason_;
};

}  // namespace alight::tools
