#pragma once
// CRC-16/MCRF4XX, the checksum of every MAVLink frame (mavlink.io/en/guide/serialization.html,
// "Checksum"): polynomial 0x1021 processed LSB first (reflected: 0x8408), initial value 0xFFFF, no
// final XOR. Check value over the ASCII digits "123456789": 0x6F91. The frame's checksum covers
// every byte after the start marker up to the end of the payload, then the message's CRC_EXTRA.

#include <array>
#include <cstddef>
#include <cstdint>

namespace alight::mavlink {

inline constexpr uint16_t kCrcInit = 0xFFFF;

namespace detail {
constexpr std::array<uint16_t, 256> make_crc_table() {
  std::array<uint16_t, 256> table{};
  for (unsigned i = 0; i < 256; ++i) {
    uint16_t r = static_cast<uint16_t>(i);
    for (int bit = 0; bit < 8; ++bit)
      r = (r & 1u) ? static_cast<uint16_t>((r >> 1) ^ 0x8408u) : (r >> 1);
    table[i] = r;
  }
  return table;
}
inline constexpr std::array<uint16_t, 256> kCrcTable = make_crc_table();
}  // namespace detail

/// One byte into a running CRC.
constexpr uint16_t crc_accumulate(uint8_t byte, uint16_t crc) {
  return static_cast<uint16_t>((crc >> 8) ^ detail::kCrcTable[(crc ^ byte) & 0xFFu]);
}

/// `n` bytes into a running CRC (start with kCrcInit).
constexpr uint16_t crc_accumulate(const uint8_t* data, size_t n, uint16_t crc) {
  for (size_t i = 0; i < n; ++i) crc = crc_accumulate(data[i], crc);
  return crc;
}

/// CRC-16/MCRF4XX of `n` bytes.
constexpr uint16_t crc16_mcrf4xx(const uint8_t* data, size_t n) {
  return crc_accumulate(data, n, kCrcInit);
}

}  // namespace alight::mavlink
