#pragma once
// Scores a flown mission from its session log: the figures the paper reports (touchdown on the
// platform, Fig. 10; platform height, Fig. 11; opening width, Fig. 12) measured against the
// simulator's ground truth (SIM_TRUTH), which flight code never sees. Pure: fed decoded
// messages in log order; alight-score does the file reading.

#include <alight/autonomy_status_t.hpp>
#include <alight/sim_truth_t.hpp>
#include <alight/target_t.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace alight::tools {

struct Score {
  std::string scenario;
  int mission = 0;          ///< target_t::MISSION_*
  bool success = false;     ///< landed on the platform / flew through without contact
  std::string outcome;      ///< landed, tipped, not_landed, through, collided, left_area, incomplete
  std::string final_phase;  ///< last AUTONOMY_STATUS phase name
  std::optional<double> mission_time_s;             ///< GO (detection starts) to LANDED / DONE
  std::optional<double> touchdown_lateral_error_m;  ///< body origin to platform centre, in xy
  std::optional<double> platform_height_error_m;    ///< converged estimate z - true top z
  std::optional<double> vision_height_error_m;      ///< median vision platform height - truth
  std::optional<double> opening_width_error_m;      ///< median vision opening width - truth
  std::optional<double> opening_center_error_m;     ///< converged estimate to true centre [m]
  std::optional<double> crossing_offset_m;          ///< wall-plane offset from centre when crossing
  int n_measurements = 0;                           ///< waypoints in the final estimate
  int vision_frames = 0;                            ///< VISION_TARGET messages
  int vision_found = 0;                             ///< ... with a target
  bool collided = false;
  int n_collisions = 0;
  bool out_of_area = false;  ///< the vehicle left the flying area (fails any mission)

  /// `key: value` lines (absent figures are left out).
  std::string to_text() const;
  std::string to_json() const;
  std::vector<std::pair<std::string, std::string>> fields() const;
};

class Scorer {
 public:
  void add(const sim_truth_t& truth);
  void add(const autonomy_status_t& status);
  void add(const target_t& target);
  Score result() const;

 private:
  std::optional<sim_truth_t> last_truth_, touchdown_truth_;
  std::optional<sim_truth_t> before_crossing_, after_crossing_;
  std::optional<autonomy_status_t> last_status_, converged_status_;
  std::optional<int64_t> go_utime_, end_utime_;
  std::vector<double> widths_m_, heights_m_;
  int mission_ = 0;
  bool tipped_ = false;  // any sample: the vehicle fell off an edge
  int vision_frames_ = 0, vision_found_ = 0;
};

}  // namespace alight::tools
