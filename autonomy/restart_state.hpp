#pragma once
// The autonomy's memory across a restart of its process: the latches a restart must
// not forget (KILL, a failsafe) and whether it was flying, kept by the node in a small state file.
//
// Why a file owned by the node rather than state derived from LCM: a KILL is a decision, not a
// measurement. Nothing on LCM says reliably that one was given: the last AUTONOMY_STATUS may be
// lost, and the outer loop's ATTITUDE_CMD armed=false looks the same after a KILL as after a
// landing. A file written on every change (write + rename: a reader sees the old or the new
// record, never half of one, whenever the writer dies) is exact. What LCM does tell -- the pose
// -- the autonomy still judges itself on the first pose (autonomy.hpp, "Restart").
//
// A record is restored only by the same session: same boot (boot id), same parent process (the
// launcher that restarts the node), and heartbeat (rewritten every second) no older than
// restart.state_max_age_s. A new launch is a new flight and starts clean; a KILL is cleared by
// stopping the session, as a kill switch is by power-cycling.
//
// Parsing and the restore decision are pure (tested without files); the file functions are for
// the node only.

#include <cstdint>
#include <optional>
#include <string>

#include "autonomy/types.hpp"
#include "common/boot_id.hpp"

namespace alight::autonomy {

struct RestartRecord {
  std::string boot_id;       ///< /proc/sys/kernel/random/boot_id of the writer
  int64_t session = 0;       ///< the writer's parent process id (the launcher)
  int64_t steady_utime = 0;  ///< when it was written, on the steady clock (one per boot) [us]
  RestartState state;
};

std::string format_record(const RestartRecord& r);
/// nullopt with *why for anything but a complete record of this version.
std::optional<RestartRecord> parse_record(const std::string& text, std::string* why);

/// The state to restore: the record's when it comes from this boot and session and is at most
/// max_age_s old, else a fresh start. *why says which.
RestartState restore_state(const std::optional<RestartRecord>& record, const std::string& boot_id,
                           int64_t session, int64_t steady_now_utime, double max_age_s,
                           std::string* why);

// --- Node side (file system) ---

/// ${XDG_RUNTIME_DIR}/alight or /tmp/alight-<uid>, then alight-autonomy-<hash of lcm_url>.state:
/// one per LCM network, so simulations on other ports never share a file.
std::string default_state_path(const std::string& lcm_url);
/// The kernel's boot id ("" when unreadable).
using alight::read_boot_id;
/// Reads at most 4 KiB; nullopt with *why when missing or unreadable.
std::optional<std::string> read_state_file(const std::string& path, std::string* why);
/// Writes `text` to path.tmp and renames it over `path` (atomic against the writer's death),
/// creating the directory (0700) when missing. false with *why on failure.
bool write_state_file(const std::string& path, const std::string& text, std::string* why);

}  // namespace alight::autonomy
