#pragma once
// Conversions between the simulator's domain structs and the LCM messages the node publishes
// (MOCAP_POSE, IMU, RANGE, BARO, CAMERA, SIM_TRUTH, SIM_PLATFORM) and consumes (ATTITUDE_CMD).

#include <alight/attitude_cmd_t.hpp>
#include <alight/baro_t.hpp>
#include <alight/image_t.hpp>
#include <alight/imu_t.hpp>
#include <alight/platform_truth_t.hpp>
#include <alight/pose_t.hpp>
#include <alight/range_t.hpp>
#include <alight/sim_truth_t.hpp>
#include <optional>
#include <string>

#include "sim/simulator.hpp"

namespace alight::sim {

pose_t to_msg(const MocapSample& sample);
imu_t to_msg(const ImuSample& sample);
/// RangeStatus maps onto range_t::STATUS_* (same values).
range_t to_msg(const RangeSample& sample);
baro_t to_msg(const BaroSample& sample);
/// mono8 frame stamped at mid-exposure, with "seq" and "exposure_us" metadata.
image_t to_msg(const CameraFrame& frame);
sim_truth_t to_msg(const Truth& truth);
/// SIM_PLATFORM: the moving platform's pose and velocities at the truth's time; nullopt for a
/// platform standing still or none.
std::optional<platform_truth_t> platform_msg(const Truth& truth);
AttitudeCommand from_msg(const attitude_cmd_t& msg);
/// Validating form for untrusted input: nullopt (and *why, when given) for a non-finite angle,
/// rate or thrust.
std::optional<AttitudeCommand> command_from_msg(const attitude_cmd_t& msg, std::string* why);
/// How far ahead of the simulated autopilot's clock a command may be stamped [s]. The outer loop
/// stamps commands on its own estimate of the vehicle's clock (newest input plus steady time
/// since), which runs ahead while the simulator is starved of CPU behind real time.
inline constexpr double kMaxCommandAheadS = 10.0;
/// The same, also refusing a command stamped more than `max_age_s` before the simulated
/// autopilot's clock `now_utime` (an autopilot would have given up waiting for a command that
/// old: its command-loss timeout; so it is a replay or a stray sender) or more than
/// kMaxCommandAheadS after it. Not a per-source monotonic check: the outer loop's stamps step
/// back legitimately when a pose arrives after a timer tick that extrapolated its clock.
std::optional<AttitudeCommand> command_from_msg(const attitude_cmd_t& msg, int64_t now_utime,
                                                double max_age_s, std::string* why);

}  // namespace alight::sim
