#pragma once
// This boot of the computer: the kernel's random boot id. Within one boot the steady clock
// (CLOCK_MONOTONIC) runs on across process restarts, so a restarted node can age a record it
// wrote by the steady clock, whatever the wall clock says (a computer without a real-time clock
// before NTP). Node side: reads /proc.

#include <string>

namespace alight {

/// /proc/sys/kernel/random/boot_id, or "" where there is none.
std::string read_boot_id();

}  // namespace alight
