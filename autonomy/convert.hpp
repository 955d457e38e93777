#pragma once
// LCM <-> domain conversions of the autonomy loop's messages (no network; tested in
// test/autonomy/convert_test.cpp). The setpoint uses outer_loop/convert.hpp.

#include <alight/autonomy_status_t.hpp>
#include <alight/imu_t.hpp>
#include <alight/operator_cmd_t.hpp>
#include <alight/platform_motion_t.hpp>
#include <alight/state_estimate_t.hpp>
#include <alight/target_t.hpp>
#include <optional>
#include <string>

#include "autonomy/types.hpp"

namespace alight::autonomy {

ImuSample from_msg(const imu_t& msg);
TargetMeasurement from_msg(const target_t& msg);
OperatorCommand from_msg(const operator_cmd_t& msg);
/// The health of an estimate (an unknown health code reads as LOST; estimate_from_msg refuses it).
EstimateHealth from_msg(const state_estimate_t& msg);
/// state_estimate_t.REASON_* bits as names, "no_flow|no_range" (unknown bits as "bit_12").
std::string estimate_reasons_text(uint32_t reasons);

/// Validating forms for untrusted input (the node uses only these): nullopt, with *why naming
/// the field, for a message the autonomy must not act on. The node counts it (reject_value) and
/// keeps the last good one.
///  - IMU: non-finite, or beyond any MEMS range (|accel| > kMaxAccelMps2 per axis, |gyro| >
///    kMaxGyroRadps): an Inf sample would count as a touch-down impact and cut the motors.
///  - Target: non-finite position, normal, size or yaw; a zero normal; a negative size. A NaN
///    size_m would skip the vehicle-fits-the-opening check.
///  - Command: a non-finite or absurd (> kMaxNudgeM) NUDGE offset (NaN passed the geofence
///    clamp); an unknown command code. The signature is not judged here (the node's verifier).
///  - Estimate: an unknown health code; a non-finite number anywhere; an orientation off the
///    unit sphere; a negative variance; a position beyond kMaxEstimatePositionM. Only the health
///    is used, but such an estimate is broken whatever its health says; refused, it counts as
///    silent, and a silent estimate is LOST after failsafe.estimate_silent_s.
inline constexpr double kMaxAccelMps2 = 1000.0;  // ~100 g: above any flight IMU's range
inline constexpr double kMaxGyroRadps = 100.0;   // ~5700 deg/s
inline constexpr double kMaxNudgeM = 100.0;      // the autonomy clamps to max_nudge_m anyway
inline constexpr double kMaxQuaternionNormError = 0.01;   // as pose_from_msg
inline constexpr double kMaxEstimatePositionM = 10000.0;  // 10 km from the origin: diverged
std::optional<ImuSample> imu_from_msg(const imu_t& msg, std::string* why);
std::optional<TargetMeasurement> target_from_msg(const target_t& msg, std::string* why);
/// A found VISION_PLATFORM measurement; nullopt (why empty) for one not found, refused (why
/// says) for a newer version, non-finite fields, negative variances or an earlier frame not
/// before the current one.
std::optional<PlatformMeasurement> platform_from_msg(const platform_motion_t& msg,
                                                     std::string* why);
/// The message form of a measurement, for tests.
platform_motion_t to_msg(const PlatformMeasurement& m, int64_t seq);
std::optional<OperatorCommand> command_from_msg(const operator_cmd_t& msg, std::string* why);
std::optional<EstimateHealth> estimate_from_msg(const state_estimate_t& msg, std::string* why);
autonomy_status_t to_msg(const Status& status);

int8_t mission_to_msg(Mission m);
Mission mission_from_msg(int8_t m);
int8_t phase_to_msg(Phase p);
int8_t failsafe_to_msg(Failsafe f);

/// Message forms for tests and tools that produce inputs.
imu_t to_msg(const ImuSample& imu, int64_t seq);
target_t to_msg(const TargetMeasurement& m, int64_t seq);
/// An estimate with this health, at rest at the origin (identity orientation, small variances).
state_estimate_t to_msg(const EstimateHealth& e, int64_t seq);

}  // namespace alight::autonomy
