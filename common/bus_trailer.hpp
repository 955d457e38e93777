#pragma once
// The size and magic of the origin trailer every alight publisher appends to a message
// (common/bus_auth.hpp), for code that only needs to find the message in front of it: log
// readers, decode_message(). No dependencies.

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>

namespace alight::bus {

inline constexpr size_t kTrailerBytes = 38;
inline constexpr std::array<uint8_t, 4> kMagic = {'A', 'L', 'B', '1'};

/// True when the `size` bytes at `data` end in an origin trailer.
inline bool has_trailer(const void* data, size_t size) {
  return data != nullptr && size >= kTrailerBytes &&
         std::memcmp(static_cast<const uint8_t*>(data) + size - kMagic.size(), kMagic.data(),
                     kMagic.size()) == 0;
}

/// The length of the lcm-gen message in front of a trailer (all of `size` when there is none).
inline size_t payload_size(const void* data, size_t size) {
  return has_trailer(data, size) ? size - kTrailerBytes : size;
}

}  // namespace alight::bus
