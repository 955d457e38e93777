#pragma once
// Between LCM messages and the estimator's structs (no network): imu_t, range_t and baro_t in,
// state_estimate_t and pose_t out. Values are judged by the estimator itself (Outcome), which
// counts what it refuses; these only translate.

#include <alight/baro_t.hpp>
#include <alight/imu_t.hpp>
#include <alight/pose_t.hpp>
#include <alight/range_t.hpp>
#include <alight/state_estimate_t.hpp>

#include "estimator/types.hpp"

namespace alight::estimator {

ImuSample from_msg(const imu_t& msg);
/// valid only for STATUS_OK (any other status carries no distance).
RangeSample from_msg(const range_t& msg);
BaroSample from_msg(const baro_t& msg);

/// The estimate at its newest IMU sample; `gyro_B` is that sample's rate (the bias is taken off).
state_estimate_t to_msg(const State& s, const Vector3d& gyro_B, int64_t seq);
/// The same pose as a pose_t (ESTIMATE_POSE), status COASTING unless the health is OK.
pose_t to_pose_msg(const State& s, const Vector3d& gyro_B, int64_t seq);

}  // namespace alight::estimator
