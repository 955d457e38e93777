#pragma once
// Safe decoding of untrusted LCM bytes. lcm-gen's C++ decoders (LCM 1.3.1) trust the counts in
// the message: a string length of 0 makes them throw std::length_error, and an array count is
// used to allocate before the bytes behind it are checked, so a 40-byte image_t can ask for 2 GiB.
// decode_message() walks the variable-length parts of the types that have them before decoding
// (no allocation), catches whatever the generated code throws, and demands that the message use
// the whole buffer. It never throws.

#include <alight/image_t.hpp>
#include <alight/process_status_t.hpp>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <limits>

#include "common/bus_trailer.hpp"

namespace alight {

namespace wire {

/// Big-endian reader over an untrusted buffer; every read is bounds-checked.
class Reader {
 public:
  Reader(const void* data, size_t size) : p_(static_cast<const uint8_t*>(data)), size_(size) {}
  bool skip(int64_t n) {
    if (n < 0 || static_cast<uint64_t>(n) > size_ - pos_) return false;
    pos_ += static_cast<size_t>(n);
    return true;
  }
  bool int32(int32_t& v) {
    if (size_ - pos_ < 4) return false;
    uint32_t u = 0;
    for (int i = 0; i < 4; ++i) u = (u << 8) | p_[pos_ + i];
    pos_ += 4;
    v = static_cast<int32_t>(u);
    return true;
  }
  /// An LCM string: int32 length including the terminating NUL, then the bytes.
  bool string() {
    int32_t n = 0;
    return int32(n) && n >= 1 && skip(n);
  }
  size_t remaining() const { return size_ - pos_; }

 private:
  const uint8_t* p_;
  size_t size_;
  size_t pos_ = 0;
};

/// Structural check of the encoded bytes before lcm-gen allocates anything. The generic case has
/// no variable-length array worth checking (strings are bounded by catching, below).
template <class Msg>
inline bool precheck(const void*, size_t) {
  return true;
}

template <>
inline bool precheck<image_t>(const void* data, size_t size) {
  // fingerprint, utime, width, height, row_stride, pixelformat
  Reader r(data, size);
  int32_t n = 0;
  if (!r.skip(8 + 8 + 4 * 4) || !r.int32(n) || n < 0 || !r.skip(n)) return false;
  if (!r.int32(n) || n < 0) return false;
  for (int32_t i = 0; i < n; ++i) {  // image_metadata_t: key, n, value[n] (no fingerprint)
    int32_t len = 0;
    if (!r.string() || !r.int32(len) || len < 0 || !r.skip(len)) return false;
  }
  return true;
}

template <>
inline bool precheck<process_status_t>(const void* data, size_t size) {
  Reader r(data, size);
  int32_t n = 0;
  if (!r.skip(8 + 8) || !r.string() || !r.string() || !r.int32(n) || n < 0) return false;
  // Each process_info_t takes at least 37 bytes (a 1-byte string and 33 bytes of fields).
  return static_cast<uint64_t>(n) * 37 <= r.remaining();
}

}  // namespace wire

/// Decodes `size` bytes into `msg`. False (msg unspecified) when the bytes are not exactly one
/// well-formed message of type Msg (followed by nothing but an origin trailer,
/// common/bus_trailer.hpp): wrong fingerprint, truncated, trailing bytes, impossible counts or
/// lengths. The trailer is not judged here (the node's Gatekeeper does that).
template <class Msg>
bool decode_message(Msg& msg, const void* data, size_t size) noexcept {
  if (data == nullptr || size > static_cast<size_t>(std::numeric_limits<int>::max())) return false;
  size = bus::payload_size(data, size);
  if (!wire::precheck<Msg>(data, size)) return false;
  try {
    return msg.decode(data, 0, static_cast<int>(size)) == static_cast<int>(size);
  } catch (const std::exception&) {
    return false;
  }
}

}  // namespace alight
