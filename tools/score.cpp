#include "tools/score.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <unordered_set>

#include "sim/params.hpp"

namespace alight::tools {

namespace {
double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}
// Nearest rank: the smallest value with at least `percent` % of the values at or below it.
double percentile(const std::vector<double>& sorted, int percent) {
  const size_t n = sorted.size();
  const size_t rank = (static_cast<size_t>(percent) * n + 99) / 100;  // ceil(percent * n / 100)
  return sorted[std::clamp<size_t>(rank, 1, n) - 1];
}
double dist_xy(const double a[3], const double b[3]) {
  return std::hypot(a[0] - b[0], a[1] - b[1]);
}
// Signed distance of the vehicle from the wall plane, positive on the approach side.
double wall_side(const sim_truth_t& t) {
  double s = 0;
  for (int i = 0; i < 3; ++i) s += (t.pos[i] - t.opening_center_W[i]) * t.wall_normal_W[i];
  return s;
}
bool on_ground(int8_t contact) {
  return contact == sim_truth_t::CONTACT_FLOOR || contact == sim_truth_t::CONTACT_PLATFORM_TOP ||
         contact == sim_truth_t::CONTACT_PLATFORM_EDGE;
}
Eigen::Quaterniond quat(const double q[4]) {
  return Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized();
}
// The vehicle's sink rate relative to the deck: the deck's velocity at the vehicle's position
// (its centre's plus the turn's), along the deck's normal.
double relative_sink_mps(const sim_truth_t& t, const platform_truth_t& p) {
  const Eigen::Vector3d pos(t.pos[0], t.pos[1], t.pos[2]);
  const Eigen::Vector3d top(p.top_center_W[0], p.top_center_W[1], p.top_center_W[2]);
  const Eigen::Vector3d v_deck =
      Eigen::Vector3d(p.vel_W[0], p.vel_W[1], p.vel_W[2]) +
      Eigen::Vector3d(p.omega_W[0], p.omega_W[1], p.omega_W[2]).cross(pos - top);
  const Eigen::Vector3d n = quat(p.orientation).toRotationMatrix().col(2);
  return -(Eigen::Vector3d(t.vel[0], t.vel[1], t.vel[2]) - v_deck).dot(n);
}
// |vehicle heading - platform heading| folded to [0, 45] deg: the angle of the body's axes to the
// nearer of the top's edges. The gear is square and autonomy turns it to the edges modulo 90 deg
// (autonomy.landing.align_yaw_tol_deg, moving_landing.hpp), as the in-process closed loop scores
// it (test/autonomy/closed_loop.cpp).
double heading_error_deg(const sim_truth_t& t, const platform_truth_t& p) {
  const Eigen::Vector3d x = quat(t.orientation).toRotationMatrix().col(0);
  double d = std::atan2(x.y(), x.x()) - p.yaw_rad;
  d = std::remainder(d, M_PI / 2);  // in [-pi/4, pi/4]
  return std::abs(d) * 180.0 / M_PI;
}
std::string fmt(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4f", v);
  return buf;
}
}  // namespace

Scorer::Scorer() : Scorer(sim::VehicleParams{}.gear_max_impact_mps) {}

Scorer::Scorer(double gear_max_impact_mps) : gear_max_impact_mps_(gear_max_impact_mps) {}

void Scorer::add(const platform_truth_t& p) {
  if (p.version > platform_truth_t::VERSION) {
    ++platform_refused_;
    return;
  }
  platform_ = p;
}

void Scorer::add(const sim_truth_t& t) {
  tipped_ = tipped_ || t.tipped;
  // The platform of this sample: SIM_PLATFORM comes just before its SIM_TRUTH.
  const std::optional<platform_truth_t> platform =
      platform_ && platform_->utime == t.utime ? platform_ : std::nullopt;
  const bool onto_platform = t.contact == sim_truth_t::CONTACT_PLATFORM_TOP ||
                             t.contact == sim_truth_t::CONTACT_PLATFORM_EDGE;
  if (last_truth_ && on_ground(t.contact) && !on_ground(last_truth_->contact)) {
    // SIM_TRUTH comes every 20 ms: the sample before the contact may be up to 20 ms short of
    // the impact (falling faster by then), the one after up to 20 ms into the gear's springs
    // (already slowed); the faster of the two is the nearer to the impact.
    double sink = std::max({0.0, -last_truth_->vel[2], -t.vel[2]});
    if (onto_platform && platform && last_truth_platform_) {
      // Onto a moving deck: what the gear takes is the speed relative to the deck.
      sink = std::max({0.0, relative_sink_mps(*last_truth_, *last_truth_platform_),
                       relative_sink_mps(t, *platform)});
      if (!platform_touched_ && t.contact == sim_truth_t::CONTACT_PLATFORM_TOP) {
        platform_touched_ = true;
        relative_sink_mps_ = sink;
        heading_error_deg_ = heading_error_deg(t, *platform);
        platform_speed_mps_ = std::sqrt(platform->vel_W[0] * platform->vel_W[0] +
                                        platform->vel_W[1] * platform->vel_W[1] +
                                        platform->vel_W[2] * platform->vel_W[2]);
      }
    }
    max_touchdown_speed_mps_ = std::max(max_touchdown_speed_mps_.value_or(0.0), sink);
  }
  if (t.has_platform && !touchdown_truth_ && (t.landed || t.tipped)) {
    touchdown_truth_ = t;
    touchdown_platform_ = platform;
  }
  last_truth_platform_ = platform;
  if (t.has_opening && !after_crossing_) {
    if (wall_side(t) >= 0) {
      before_crossing_ = t;
    } else if (before_crossing_) {
      after_crossing_ = t;
    }
  }
  last_truth_ = t;
}

void Scorer::add(const autonomy_status_t& s) {
  if (s.mission != 0) mission_ = s.mission;
  if (!go_utime_ && s.phase == autonomy_status_t::PHASE_DETECTION) go_utime_ = s.utime;
  // The estimate at convergence: the first status after refinement that carries it.
  if (!converged_status_ && s.has_estimate &&
      (s.phase == autonomy_status_t::PHASE_APPROACH ||
       s.phase == autonomy_status_t::PHASE_FINAL_DESCENT))
    converged_status_ = s;
  if (!end_utime_ &&
      (s.phase == autonomy_status_t::PHASE_LANDED || s.phase == autonomy_status_t::PHASE_DONE))
    end_utime_ = s.utime;
  last_status_ = s;
}

void Scorer::add(const target_t& t) {
  ++vision_frames_;
  if (!t.found) return;
  ++vision_found_;
  if (t.mission != 0) mission_ = t.mission;
  if (t.mission == target_t::MISSION_INGRESS && t.size_m[0] > 0) widths_m_.push_back(t.size_m[0]);
  if (t.mission == target_t::MISSION_LANDING && t.target_height_m > 0)
    heights_m_.push_back(t.target_height_m);
}

void Scorer::add(const target_t& t, int64_t received_utime) {
  target_received_.emplace_back(t.utime, received_utime);
  if (t.reason == target_t::REASON_NO_POSE) without_pose_.insert(t.utime);
  if (t.found) ++timed_found_;
  extend_span(received_utime);
  add(t);
}

void Scorer::add(const vision_timing_t& t) {
  process_ms_.push_back(1e-3 * static_cast<double>(t.process_us));
  process_cpu_ms_.push_back(1e-3 * static_cast<double>(t.process_cpu_us));
  wait_ms_.push_back(1e-3 * static_cast<double>(t.wait_us));
  // Counters only grow; the logger may lose or reorder a message, so the largest wins.
  if (!last_timing_ || t.frames_processed >= last_timing_->frames_processed) last_timing_ = t;
}

void Scorer::add_camera_frame(int64_t image_utime, int64_t received_utime) {
  ++camera_frames_;
  camera_received_.emplace(image_utime, received_utime);
  if (!first_camera_) first_camera_ = {image_utime, received_utime};
  last_camera_ = {image_utime, received_utime};
  extend_span(received_utime);
}

void Scorer::extend_span(int64_t received_utime) {
  if (!first_received_ || received_utime < *first_received_) first_received_ = received_utime;
  if (!last_received_ || received_utime > *last_received_) last_received_ = received_utime;
}

namespace {
std::optional<Score::Percentiles> percentiles(std::vector<double> v) {
  if (v.empty()) return std::nullopt;
  std::sort(v.begin(), v.end());
  return Score::Percentiles{percentile(v, 50), percentile(v, 90), percentile(v, 99), v.back()};
}

// Exposure stamps further than this from the logger's clock are not wall-clock stamps.
constexpr double kMaxEndToEndMs = 60'000.0;

void timing(const std::unordered_map<int64_t, int64_t>& camera_received,
            const std::vector<std::pair<int64_t, int64_t>>& target_received,
            const std::unordered_set<int64_t>& without_pose, Score& s) {
  std::vector<double> latencies_ms;
  std::unordered_set<int64_t> covered;
  for (const auto& [image_utime, received] : target_received) {
    const auto it = camera_received.find(image_utime);
    if (it == camera_received.end()) {
      ++s.vision_latency_unmatched;
      continue;
    }
    covered.insert(image_utime);
    if (without_pose.count(image_utime)) {
      ++s.vision_latency_without_pose;
      continue;
    }
    latencies_ms.push_back(1e-3 * static_cast<double>(received - it->second));
  }
  if (!latencies_ms.empty()) {
    std::sort(latencies_ms.begin(), latencies_ms.end());
    s.vision_latency_p50_ms = percentile(latencies_ms, 50);
    s.vision_latency_p99_ms = percentile(latencies_ms, 99);
    s.vision_latency_max_ms = latencies_ms.back();
  }
  if (!camera_received.empty())
    s.vision_frame_coverage =
        static_cast<double>(covered.size()) / static_cast<double>(camera_received.size());
}
}  // namespace

Score Scorer::result() const {
  Score s;
  s.gear_max_impact_mps = gear_max_impact_mps_;
  s.vision_frames = vision_frames_;
  s.vision_found = vision_found_;
  s.camera_frames = camera_frames_;
  timing(camera_received_, target_received_, without_pose_, s);
  s.timing_frames = static_cast<int>(process_ms_.size());
  s.vision_process_ms = percentiles(process_ms_);
  s.vision_process_cpu_ms = percentiles(process_cpu_ms_);
  s.vision_wait_ms = percentiles(wait_ms_);
  if (last_timing_) {
    s.vision_frames_received = last_timing_->frames_received;
    s.vision_frames_dropped = last_timing_->frames_dropped;
    s.vision_frames_refused = last_timing_->frames_refused;
    s.vision_frames_failed = last_timing_->frames_failed;
    s.vision_frames_processed = last_timing_->frames_processed;
    s.vision_frames_waiting = last_timing_->frames_waiting;
    s.vision_frames_late = last_timing_->frames_late;
    std::vector<double> e2e_ms;
    for (const auto& [exposure, received] : target_received_)
      e2e_ms.push_back(1e-3 * static_cast<double>(received - exposure));
    const auto e2e = percentiles(e2e_ms);
    if (e2e && e2e->p50 >= 0 && e2e->p50 <= kMaxEndToEndMs) s.vision_end_to_end_ms = e2e;
  }
  if (first_received_ && *last_received_ > *first_received_) {
    const double span_s = 1e-6 * static_cast<double>(*last_received_ - *first_received_);
    if (camera_frames_ > 0) s.camera_frames_per_s = camera_frames_ / span_s;
    if (!target_received_.empty()) {
      s.vision_frames_per_s = static_cast<double>(target_received_.size()) / span_s;
      s.vision_waypoints_per_s = timed_found_ / span_s;
    }
  }
  if (first_camera_ && last_camera_->second > first_camera_->second)
    s.real_time_factor = static_cast<double>(last_camera_->first - first_camera_->first) /
                         static_cast<double>(last_camera_->second - first_camera_->second);
  if (last_status_) {
    s.final_phase = last_status_->phase_name;
    s.n_measurements = last_status_->n_measurements;
  }
  if (go_utime_ && end_utime_)
    s.mission_time_s = 1e-6 * static_cast<double>(*end_utime_ - *go_utime_);
  if (!last_truth_) {
    s.outcome = "incomplete";
    return s;
  }
  const sim_truth_t& truth = *last_truth_;
  s.scenario = truth.scenario;
  s.collided = truth.collided;
  s.n_collisions = truth.n_collisions;
  s.max_touchdown_speed_mps = max_touchdown_speed_mps_;
  s.crashed = max_touchdown_speed_mps_ && *max_touchdown_speed_mps_ > gear_max_impact_mps_;
  s.out_of_area = truth.out_of_area;
  s.platform_moving = platform_.has_value();
  s.touchdown_relative_sink_mps = relative_sink_mps_;
  s.touchdown_heading_error_deg = heading_error_deg_;
  s.touchdown_platform_speed_mps = platform_speed_mps_;
  s.platform_messages_refused = platform_refused_;
  s.mission = mission_ ? mission_
                       : (truth.has_platform ? target_t::MISSION_LANDING
                                             : (truth.has_opening ? target_t::MISSION_INGRESS : 0));
  if (truth.has_platform) {
    // Against the platform where it was at touch-down (a still one is where it always was).
    if (touchdown_truth_)
      s.touchdown_lateral_error_m =
          dist_xy(touchdown_truth_->pos, touchdown_platform_ ? touchdown_platform_->top_center_W
                                                             : truth.platform_center_W);
    if (converged_status_)
      s.platform_height_error_m = converged_status_->estimate_W[2] - truth.platform_center_W[2];
    if (!heights_m_.empty())
      s.vision_height_error_m = median(heights_m_) - truth.platform_size_m[2];
  }
  if (truth.has_opening) {
    if (!widths_m_.empty()) s.opening_width_error_m = median(widths_m_) - truth.opening_size_m[0];
    if (converged_status_) {
      double d2 = 0;
      for (int i = 0; i < 3; ++i)
        d2 += std::pow(converged_status_->estimate_W[i] - truth.opening_center_W[i], 2);
      s.opening_center_error_m = std::sqrt(d2);
    }
    if (after_crossing_) {
      // Interpolate the crossing point between the samples either side of the wall plane.
      const double a = wall_side(*before_crossing_), b = wall_side(*after_crossing_);
      const double f = a / (a - b);
      double off2 = 0;
      for (int i = 0; i < 3; ++i) {
        const double p =
            before_crossing_->pos[i] + f * (after_crossing_->pos[i] - before_crossing_->pos[i]);
        const double d = p - truth.opening_center_W[i];
        off2 += d * d;
      }
      s.crossing_offset_m = std::sqrt(off2);
    }
  }
  if (s.mission == target_t::MISSION_LANDING) {
    s.outcome = tipped_ ? "tipped" : (truth.landed ? "landed" : "not_landed");
    s.success = truth.landed && !tipped_;
  } else if (s.mission == target_t::MISSION_INGRESS) {
    const bool done = last_status_ && last_status_->phase == autonomy_status_t::PHASE_DONE;
    s.outcome = truth.collided ? "collided" : (after_crossing_ ? "through" : "incomplete");
    // Autonomy's refusal of an opening the vehicle does not fit through (the paper's 60 cm
    // window for a 67 cm vehicle) is the right end of such a flight, not an unfinished one.
    if (s.outcome == "incomplete" && last_status_ &&
        last_status_->phase == autonomy_status_t::PHASE_HOLD &&
        last_status_->reason.rfind("refused", 0) == 0)
      s.outcome = "refused";
    s.success = !truth.collided && after_crossing_.has_value() && done;
  } else {
    s.outcome = "incomplete";
  }
  // Upright and on target or not: a real vehicle would have broken its gear, or worse.
  if (s.crashed) {
    s.outcome = "crashed";
    s.success = false;
  }
  // Out there a real flight would have lost its motion capture or hit the hall: whatever
  // happened afterwards does not count.
  if (truth.out_of_area && s.mission != 0) {
    s.outcome = "left_area";
    s.success = false;
  }
  return s;
}

std::vector<std::pair<std::string, std::string>> Score::fields() const {
  std::vector<std::pair<std::string, std::string>> f;
  f.emplace_back("scenario", scenario);
  f.emplace_back("mission", mission == target_t::MISSION_LANDING   ? "landing"
                            : mission == target_t::MISSION_INGRESS ? "ingress"
                                                                   : "none");
  f.emplace_back("success", success ? "true" : "false");
  f.emplace_back("outcome", outcome);
  f.emplace_back("final_phase", final_phase);
  auto opt = [&](const char* key, const std::optional<double>& v) {
    if (v) f.emplace_back(key, fmt(*v));
  };
  opt("mission_time_s", mission_time_s);
  opt("touchdown_lateral_error_m", touchdown_lateral_error_m);
  opt("max_touchdown_speed_mps", max_touchdown_speed_mps);
  if (max_touchdown_speed_mps) f.emplace_back("gear_max_impact_mps", fmt(gear_max_impact_mps));
  opt("platform_height_error_m", platform_height_error_m);
  opt("vision_height_error_m", vision_height_error_m);
  opt("opening_width_error_m", opening_width_error_m);
  opt("opening_center_error_m", opening_center_error_m);
  opt("crossing_offset_m", crossing_offset_m);
  f.emplace_back("n_measurements", std::to_string(n_measurements));
  f.emplace_back("vision_frames", std::to_string(vision_frames));
  f.emplace_back("vision_found", std::to_string(vision_found));
  f.emplace_back("camera_frames", std::to_string(camera_frames));
  opt("vision_latency_p50_ms", vision_latency_p50_ms);
  opt("vision_latency_p99_ms", vision_latency_p99_ms);
  opt("vision_latency_max_ms", vision_latency_max_ms);
  f.emplace_back("vision_latency_unmatched", std::to_string(vision_latency_unmatched));
  f.emplace_back("vision_latency_without_pose", std::to_string(vision_latency_without_pose));
  opt("camera_frames_per_s", camera_frames_per_s);
  opt("vision_frames_per_s", vision_frames_per_s);
  opt("vision_waypoints_per_s", vision_waypoints_per_s);
  opt("vision_frame_coverage", vision_frame_coverage);
  opt("real_time_factor", real_time_factor);
  if (timing_frames > 0) {
    f.emplace_back("timing_frames", std::to_string(timing_frames));
    auto pct = [&](const std::string& key, const std::optional<Percentiles>& p) {
      if (!p) return;
      f.emplace_back(key + "_p50_ms", fmt(p->p50));
      f.emplace_back(key + "_p90_ms", fmt(p->p90));
      f.emplace_back(key + "_p99_ms", fmt(p->p99));
      f.emplace_back(key + "_max_ms", fmt(p->max));
    };
    pct("vision_process", vision_process_ms);
    pct("vision_process_cpu", vision_process_cpu_ms);
    pct("vision_wait", vision_wait_ms);
    pct("vision_end_to_end", vision_end_to_end_ms);
    f.emplace_back("vision_frames_received", std::to_string(vision_frames_received));
    f.emplace_back("vision_frames_dropped", std::to_string(vision_frames_dropped));
    f.emplace_back("vision_frames_refused", std::to_string(vision_frames_refused));
    f.emplace_back("vision_frames_failed", std::to_string(vision_frames_failed));
    f.emplace_back("vision_frames_processed", std::to_string(vision_frames_processed));
    f.emplace_back("vision_frames_waiting", std::to_string(vision_frames_waiting));
    f.emplace_back("vision_frames_late", std::to_string(vision_frames_late));
  }
  f.emplace_back("collided", collided ? "true" : "false");
  f.emplace_back("n_collisions", std::to_string(n_collisions));
  f.emplace_back("crashed", crashed ? "true" : "false");
  f.emplace_back("out_of_area", out_of_area ? "true" : "false");
  if (platform_moving || platform_messages_refused > 0) {
    f.emplace_back("platform_moving", platform_moving ? "true" : "false");
    opt("touchdown_relative_sink_mps", touchdown_relative_sink_mps);
    opt("touchdown_heading_error_deg", touchdown_heading_error_deg);
    opt("touchdown_platform_speed_mps", touchdown_platform_speed_mps);
    f.emplace_back("platform_messages_refused", std::to_string(platform_messages_refused));
  }
  return f;
}

std::string Score::to_text() const {
  std::ostringstream os;
  for (const auto& [k, v] : fields()) os << k << ": " << v << "\n";
  return os.str();
}

std::string Score::to_json() const {
  std::ostringstream os;
  os << "{";
  bool first = true;
  for (const auto& [k, v] : fields()) {
    const bool raw = v == "true" || v == "false" ||
                     (!v.empty() && v.find_first_not_of("-0123456789.") == std::string::npos);
    os << (first ? "" : ", ") << "\"" << k << "\": ";
    if (raw) {
      os << v;
    } else {
      os << "\"";
      for (char c : v) os << (c == '"' || c == '\\' ? "\\" : "") << c;
      os << "\"";
    }
    first = false;
  }
  os << "}\n";
  return os.str();
}

}  // namespace alight::tools
