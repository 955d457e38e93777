#pragma once
// The outer loop's state file: what must survive a restart of the process (a failsafe disarm
// stays latched; a vehicle that was flying is not disarmed by a plain motors-off). Owned by the
// node; written atomically (a temporary file renamed over the old one), so a crash mid-write
// leaves the old state, never half a file.

#include <cstdint>
#include <optional>
#include <string>

#include "outer_loop/position_controller.hpp"

namespace alight::outer_loop {

struct StateRecord {
  PersistentState state;
  int64_t wall_utime = 0;    ///< when it was written [us since Unix epoch]
  std::string boot_id;       ///< the boot it was written in (common/boot_id.hpp)
  int64_t steady_utime = 0;  ///< when it was written, on the steady clock [us]
};

std::string format_state(const StateRecord& record);
/// nullopt for anything but a complete record this version wrote.
std::optional<StateRecord> parse_state(const std::string& text);

/// Writes `record` to `path` (creating its directory, mode 0700). False and *error on failure.
bool save_state(const std::string& path, const StateRecord& record, std::string* error);
/// nullopt when the file is absent or unreadable (*error says which, empty when absent).
std::optional<StateRecord> load_state(const std::string& path, std::string* error);

/// Now, for judging a record's age: the wall clock, and within the record's boot the steady
/// clock, which a wall clock far off (no real-time clock, before NTP) does not disturb.
struct RestoreClock {
  int64_t wall_utime = 0;
  std::string boot_id;
  int64_t steady_utime = 0;
};

/// What a restarted outer loop may trust `now`: a latched failsafe always; "armed" only from a
/// record written within max_age_s (the node rewrites it every second while armed), so a stale
/// file from an old session never makes a vehicle standing on the ground count as flying. The
/// age is on the steady clock when the record is of this boot, else on the wall clock.
PersistentState restored_state(const std::optional<StateRecord>& record, const RestoreClock& now,
                               double max_age_s);

/// /tmp/alight-<uid>/outer_loop-<tag>.state, `tag` (the LCM URL) reduced to [A-Za-z0-9_.-]: outer
/// loops on different LCM networks (tests on private ports, parallel sessions) never share one.
std::string default_state_path(const std::string& tag);

}  // namespace alight::outer_loop
