#pragma once
// Plausibility of message stamps at a node's input boundary. Flight logic runs on the utime of
// its inputs, so one bad stamp can stall it (an IMU sample an hour ahead held autonomy in
// FAILSAFE for good) or rewind it (an old log replayed onto the live port). Every channel is a
// source whose stamps must not go backwards, and must not run ahead of what the receiver's
// steady clock says can have elapsed since that source's last accepted stamp. A source's first
// stamp is judged against the other sources, or against the wall clock when it is the first of
// all. A source that really restarted with lower stamps (a reconnected camera, a restarted
// simulator) is taken back once it has delivered nothing newer for reset_after_s.
//
// A node whose wall clock is far behind its inputs (a companion computer without a real-time
// clock, booted before NTP) would refuse every first stamp as "ahead" forever. Instead, a source
// whose first stamps are ahead of the wall clock is watched: once its stamps have advanced in step
// with the steady clock for adopt_after_s, its stamps become the time base (verdict kAdopted,
// inputs_time_base() true) and the other sources are judged against it. A single forged stamp
// cannot do this; a genuine source near the wall clock is accepted meanwhile, and then it is the
// reference.
//
// Pure: the node passes its steady and wall clocks in.

#include <cstdint>
#include <string>
#include <unordered_map>

namespace alight {

struct StampGuardParams {
  double tolerance_s = 0.5;    ///< slack on every forward bound [s]
  double max_rate = 20.0;      ///< stamps may advance this much faster than the steady clock
                               ///< (a simulator faster than real time) [-]
  double reset_after_s = 1.0;  ///< backward stamps accepted as a restart after this long
                               ///< with nothing newer from the source [s]
  double max_first_ahead_s =
      300.0;                   ///< a first stamp this far ahead of the reference is refused [s]
  double adopt_after_s = 1.0;  ///< ... until its source has advanced in step with the steady
                               ///< clock this long: then it is the time base [s]
};

enum class StampVerdict {
  kAccepted,
  kRestarted,    ///< accepted: the source went backwards and then stayed there (a restart)
  kAdopted,      ///< accepted: far ahead of the wall clock, but steady: the inputs' time base
  kNonPositive,  ///< utime <= 0
  kBackwards,    ///< older than the source's last accepted stamp
  kAhead,        ///< further ahead than can have elapsed
};

const char* stamp_verdict_name(StampVerdict v);
inline bool stamp_ok(StampVerdict v) {
  return v == StampVerdict::kAccepted || v == StampVerdict::kRestarted ||
         v == StampVerdict::kAdopted;
}

class StampGuard {
 public:
  explicit StampGuard(StampGuardParams params = {}) : params_(params) {}

  /// Judges `utime` from `source`, received at `steady_us` (monotonic clock) and `wall_us` (Unix
  /// time). Only an accepted stamp updates the source's state.
  StampVerdict check(const std::string& source, int64_t utime, int64_t steady_us, int64_t wall_us);

  /// Newest stamp accepted from any source, 0 before the first.
  int64_t newest_utime() const { return newest_utime_; }
  /// True once the time base was taken from the inputs (the wall clock was far behind them).
  bool inputs_time_base() const { return inputs_time_base_; }
  /// Sources remembered; beyond this the longest silent is forgotten.
  static constexpr size_t kMaxSources = 64;

 private:
  struct Source {
    int64_t last_utime = 0;
    int64_t last_steady_us = 0;  // steady time at which last_utime was accepted
  };
  // The stamp every accepted source is expected to have reached by `steady_us`, at most.
  int64_t reach_us(const Source& s, int64_t steady_us) const;
  // A first stamp far ahead of the wall clock: true once its source has been steady long enough.
  bool adopt(const std::string& source, int64_t utime, int64_t steady_us);
  struct Candidate {
    int64_t first_utime = 0, first_steady_us = 0;
    int64_t last_utime = 0, last_steady_us = 0;
  };
  std::unordered_map<std::string, Candidate> candidates_;
  bool inputs_time_base_ = false;

  StampGuardParams params_;
  std::unordered_map<std::string, Source> sources_;
  int64_t newest_utime_ = 0;
};

}  // namespace alight
