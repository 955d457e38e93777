#pragma once
// LCM <-> domain conversions of the autonomy loop's messages (no network; tested in
// test/autonomy/convert_test.cpp). The setpoint uses outer_loop/convert.hpp.

#include <alight/autonomy_status_t.hpp>
#include <alight/imu_t.hpp>
#include <alight/operator_cmd_t.hpp>
#include <alight/target_t.hpp>

#include "autonomy/types.hpp"

namespace alight::autonomy {

ImuSample from_msg(const imu_t& msg);
TargetMeasurement from_msg(const target_t& msg);
OperatorCommand from_msg(const operator_cmd_t& msg);
autonomy_status_t to_msg(const Status& status);

int8_t mission_to_msg(Mission m);
Mission mission_from_msg(int8_t m);
int8_t phase_to_msg(Phase p);
int8_t failsafe_to_msg(Failsafe f);

/// Message forms for tests and tools that produce inputs.
imu_t to_msg(const ImuSample& imu, int64_t seq);
target_t to_msg(const TargetMeasurement& m, int64_t seq);

}  // namespace alight::autonomy
