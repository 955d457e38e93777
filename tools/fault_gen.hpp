#pragma once
// Fault generators of the fault campaign (scripts/faults): the bytes alight-inject
// sends onto a live channel. Pure: no LCM handle, no clock (the base message and the present
// time are passed in), randomness from a seeded engine, so a test can check that each hostile
// message is what it claims to be (e.g. that a bad string length really sits where the decoder
// reads it).
//
// Kinds, each a way an unchecked input once broke a node:
//  - garbage:     random bytes, with and without the channel's fingerprint in front (the last
//                 one the message's length: a type without lengths decodes it, random values);
//  - truncated:   a well-formed message of the channel's type cut short at several points;
//  - bad_lengths: the right fingerprint, a string or array length of 0, -1, INT32_MIN,
//                 INT32_MAX, 0x55555556 or one past the end (types without lengths: trailing
//                 bytes after a well-formed message);
//  - nan / inf:   one message per double field (all its elements non-finite), then all at once;
//  - future:      the utime an hour ahead of the base message;
//  - zero_stamp:  utime 0.

#include <cstdint>
#include <optional>
#include <random>
#include <string>
#include <vector>

namespace alight::tools::faults {

using Bytes = std::vector<uint8_t>;

enum class Kind { kGarbage, kTruncated, kBadLengths, kNaN, kInf, kFuture, kZeroStamp };

std::optional<Kind> parse_kind(const std::string& name);
std::string to_string(Kind kind);
std::vector<Kind> all_kinds();

/// The alight type carried by each channel the stack uses (and its ground station), by name.
/// Unknown channels: nullopt.
std::optional<std::string> type_of_channel(const std::string& channel);
/// Every channel of type_of_channel() except SIM_TRUTH (the referee of the campaign, which no
/// flight code reads).
std::vector<std::string> injectable_channels();

/// `size` random bytes.
Bytes garbage(std::mt19937_64& rng, size_t size);

/// One hostile message of `kind` per element, for a channel of type `type_name` (as
/// type_of_channel() names it). `base` is a well-formed encoded message of that type (the newest
/// one seen on the channel), or empty: then a plausible one stamped `now_utime` is made up.
/// Returns an empty list for an unknown type.
std::vector<Bytes> generate(Kind kind, const std::string& type_name, const Bytes& base,
                            int64_t now_utime, std::mt19937_64& rng);

/// A plausible well-formed message of `type_name` stamped `now_utime` (finite values, a unit
/// quaternion, short strings, a small image). Empty for an unknown type.
Bytes default_message(const std::string& type_name, int64_t now_utime);

/// Offsets (from the start of the encoded message, fingerprint included) of the int32 length
/// fields of `msg` that the decoder reads: string lengths and array counts. Empty when the type
/// has none, or when `msg` does not decode.
std::vector<size_t> length_field_offsets(const std::string& type_name, const Bytes& msg);

/// The utime of an encoded message (its first field, after the fingerprint), if it has one.
std::optional<int64_t> utime_of(const Bytes& msg);

}  // namespace alight::tools::faults
