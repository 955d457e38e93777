#pragma once
// The LCM messages alight-link carries, as bytes. The link forwards a message's lcm-gen encoding
// as it is (without the bus's origin trailer, which each bus's publisher writes anew), but checks
// that it is one well-formed message of the type its channel carries before it sends it or
// publishes it: the peer's messages are untrusted input like any other, and a message nobody can
// decode is refused at the link, counted, rather than at every subscriber. Pure (lcm-gen's
// generated decoders, no LCM handle).

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace alight::link {

/// A message's encoding as the link's subscriptions receive it: Node::on / on_latest decode
/// into this type, which keeps the bytes (Node has already split off and judged the trailer).
struct RawMessage {
  std::vector<uint8_t> bytes;
  /// The generated types' decode signature, so Node's typed subscriptions take it.
  int decode(const void* buf, int offset, int maxlen) {
    const auto* p = static_cast<const uint8_t*>(buf) + offset;
    bytes.assign(p, p + maxlen);
    return maxlen;
  }
};

/// True when `payload` is exactly one well-formed message of the type `channel` carries
/// (channels::message_type, decode_message: never throws, no unbounded allocation) and does not
/// itself end in an origin trailer. False for a channel that is not one of channels::kAll.
bool valid_payload(const std::string& channel, std::span<const uint8_t> payload);

}  // namespace alight::link
