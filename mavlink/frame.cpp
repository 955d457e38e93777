#include "mavlink/frame.hpp"

#include <cassert>
#include <cstring>

#include "mavlink/crc.hpp"

namespace alight::mavlink {

namespace {

void put_u16(uint8_t* p, uint16_t v) {
  p[0] = static_cast<uint8_t>(v);
  p[1] = static_cast<uint8_t>(v >> 8);
}

}  // namespace

size_t write_frame(const FrameHeader& header, uint32_t msgid, uint8_t crc_extra,
                   const uint8_t* payload, uint8_t payload_length,
                   const std::optional<SignWith>& sign, uint8_t* out) {
  assert(msgid < (1u << 24));
  out[0] = kStxV2;
  out[1] = payload_length;
  out[2] = sign ? kIncompatSigned : 0;
  out[3] = header.compat_flags;
  out[4] = header.seq;
  out[5] = header.sysid;
  out[6] = header.compid;
  out[7] = static_cast<uint8_t>(msgid);
  out[8] = static_cast<uint8_t>(msgid >> 8);
  out[9] = static_cast<uint8_t>(msgid >> 16);
  if (payload_length > 0) std::memcpy(out + kHeaderLengthV2, payload, payload_length);
  size_t n = kHeaderLengthV2 + payload_length;
  const uint16_t crc = crc_accumulate(crc_extra, crc_accumulate(out + 1, n - 1, kCrcInit));
  put_u16(out + n, crc);
  n += kChecksumLength;
  if (sign) {
    assert(sign->key != nullptr && sign->timestamp <= kMaxSigningTimestamp);
    out[n] = sign->link_id;
    for (int i = 0; i < 6; ++i) out[n + 1 + i] = static_cast<uint8_t>(sign->timestamp >> (8 * i));
    const auto value = compute_signature(*sign->key, out, n + 7);
    std::memcpy(out + n + 7, value.data(), value.size());
    n += kSignatureLength;
  }
  return n;
}

size_t write_frame_v1(const FrameHeader& header, uint8_t msgid, uint8_t crc_extra,
                      const uint8_t* payload, uint8_t payload_length, uint8_t* out) {
  out[0] = kStxV1;
  out[1] = payload_length;
  out[2] = header.seq;
  out[3] = header.sysid;
  out[4] = header.compid;
  out[5] = msgid;
  if (payload_length > 0) std::memcpy(out + kHeaderLengthV1, payload, payload_length);
  size_t n = kHeaderLengthV1 + payload_length;
  const uint16_t crc = crc_accumulate(crc_extra, crc_accumulate(out + 1, n - 1, kCrcInit));
  put_u16(out + n, crc);
  return n + kChecksumLength;
}

FrameBytes Sender::pack_payload(uint32_t msgid, uint8_t crc_extra, const uint8_t* payload,
                                uint8_t payload_length, int64_t now_unix_utime) {
  FrameBytes frame;
  std::optional<SignWith> sign;
  if (signing_) {
    // At least one more than the previous frame's, as the spec demands, even when the clock
    // stands still or steps back.
    uint64_t ts = signing_timestamp_from_unix_utime(now_unix_utime);
    if (ts <= last_timestamp_) ts = last_timestamp_ + 1;
    // 2^48 ticks of 10 us are 89 years: only a peer's absurd (but correctly signed) stamp
    // raised through raise_signing_timestamp gets here. Receivers then refuse our frames as
    // replays, which the link's failsafe handles; no arithmetic beyond 48 bits.
    if (ts > kMaxSigningTimestamp) ts = kMaxSigningTimestamp;
    last_timestamp_ = ts;
    sign = SignWith{&signing_->key, signing_->link_id, ts};
  }
  const FrameHeader header{seq_++, sysid_, compid_, 0};
  frame.size =
      write_frame(header, msgid, crc_extra, payload, payload_length, sign, frame.data.data());
  return frame;
}

}  // namespace alight::mavlink
