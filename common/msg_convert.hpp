#pragma once
// Conversions between LCM messages and domain structs: small free functions, tested without a
// network. Malformed input gives an error text, never a crash. Camera frames: image_msg.hpp.

#include <alight/pose_t.hpp>
#include <optional>
#include <string>

#include "common/pose_buffer.hpp"

namespace alight {

PoseSample from_msg(const pose_t& msg);
pose_t to_msg(const PoseSample& pose, int64_t seq);
/// Validating form of from_msg for untrusted input: nullopt (and *why, when given) unless every
/// position, velocity, orientation and rate field is finite and the quaternion's norm is within
/// 0.01 of 1 (it is then normalised; a zero one would divide by zero). The stamp is left to the
/// node's StampGuard.
std::optional<PoseSample> pose_from_msg(const pose_t& msg, std::string* why);

}  // namespace alight
