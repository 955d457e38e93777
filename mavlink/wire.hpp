#pragma once
// Payload serialization of MAVLink messages (mavlink.io/en/guide/serialization.html, "Payload
// Format"): every message lists its fields once, in wire order, through a visitor
// (`M::fields(m, v)`); the same list encodes, decodes, measures the payload and computes the
// message's CRC_EXTRA, so a field in the wrong place cannot agree with the published CRC_EXTRA
// (checked at compile time in messages.hpp).
//
// Wire order: the XML's fields sorted by the size of their (element) type, 8 bytes first, then
// 4, 2, 1, stable within one size; extension fields follow in declaration order and are not part
// of CRC_EXTRA. Little-endian whatever the host.

#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <string_view>
#include <type_traits>

#include "mavlink/crc.hpp"

namespace alight::mavlink {

/// The XML type name of a field's element type, as CRC_EXTRA hashes it.
template <class T>
constexpr std::string_view wire_type_name() {
  if constexpr (std::is_same_v<T, char>)
    return "char";
  else if constexpr (std::is_same_v<T, uint8_t>)
    return "uint8_t";
  else if constexpr (std::is_same_v<T, int8_t>)
    return "int8_t";
  else if constexpr (std::is_same_v<T, uint16_t>)
    return "uint16_t";
  else if constexpr (std::is_same_v<T, int16_t>)
    return "int16_t";
  else if constexpr (std::is_same_v<T, uint32_t>)
    return "uint32_t";
  else if constexpr (std::is_same_v<T, int32_t>)
    return "int32_t";
  else if constexpr (std::is_same_v<T, uint64_t>)
    return "uint64_t";
  else if constexpr (std::is_same_v<T, int64_t>)
    return "int64_t";
  else if constexpr (std::is_same_v<T, float>)
    return "float";
  else if constexpr (std::is_same_v<T, double>)
    return "double";
  else
    static_assert(sizeof(T) == 0, "not a MAVLink field type");
}

/// A field is a scalar or a std::array of scalars.
template <class T>
struct FieldShape {
  using Element = T;
  static constexpr size_t kCount = 1;
  static constexpr bool kIsArray = false;
};
template <class T, size_t N>
struct FieldShape<std::array<T, N>> {
  using Element = T;
  static constexpr size_t kCount = N;
  static constexpr bool kIsArray = true;
};

namespace detail {

template <class T>
using UnsignedOfSize =
    std::conditional_t<sizeof(T) == 1, uint8_t,
                       std::conditional_t<sizeof(T) == 2, uint16_t,
                                          std::conditional_t<sizeof(T) == 4, uint32_t, uint64_t>>>;

template <class T>
inline void put_le(uint8_t* p, T value) {
  const auto bits = std::bit_cast<UnsignedOfSize<T>>(value);
  for (size_t i = 0; i < sizeof(T); ++i) p[i] = static_cast<uint8_t>(bits >> (8 * i));
}

template <class T>
inline T get_le(const uint8_t* p) {
  UnsignedOfSize<T> bits = 0;
  for (size_t i = 0; i < sizeof(T); ++i)
    bits = static_cast<UnsignedOfSize<T>>(bits | (static_cast<UnsignedOfSize<T>>(p[i]) << (8 * i)));
  return std::bit_cast<T>(bits);
}

/// Writes every field at its wire offset; `out` holds at least M::kMaxLength bytes.
class PayloadWriter {
 public:
  explicit PayloadWriter(uint8_t* out) : out_(out) {}
  template <class T>
  void operator()(std::string_view, const T& field) {
    if constexpr (FieldShape<T>::kIsArray) {
      for (const auto& e : field) put(e);
    } else {
      put(field);
    }
  }
  void extensions() {}
  size_t size() const { return offset_; }

 private:
  template <class E>
  void put(E value) {
    put_le(out_ + offset_, value);
    offset_ += sizeof(E);
  }
  uint8_t* out_;
  size_t offset_ = 0;
};

/// Reads every field from its wire offset; `in` holds at least M::kMaxLength bytes, zero beyond
/// what was received (MAVLink 2 truncation, fields unknown to an older sender).
class PayloadReader {
 public:
  explicit PayloadReader(const uint8_t* in) : in_(in) {}
  template <class T>
  void operator()(std::string_view, T& field) {
    if constexpr (FieldShape<T>::kIsArray) {
      for (auto& e : field) get(e);
    } else {
      get(field);
    }
  }
  void extensions() {}

 private:
  template <class E>
  void get(E& value) {
    value = get_le<E>(in_ + offset_);
    offset_ += sizeof(E);
  }
  const uint8_t* in_;
  size_t offset_ = 0;
};

/// Base and full payload length and CRC_EXTRA from the field list (usable at compile time).
class LayoutVisitor {
 public:
  constexpr explicit LayoutVisitor(std::string_view message_name) {
    add(message_name);
    add(" ");
  }
  template <class T>
  constexpr void operator()(std::string_view name, const T&) {
    using Shape = FieldShape<T>;
    const size_t bytes = sizeof(typename Shape::Element) * Shape::kCount;
    // Sizes must never increase along the base fields: that is the wire order.
    if (!in_extensions_) {
      if (sizeof(typename Shape::Element) > last_element_size_) wire_order_ok_ = false;
      last_element_size_ = sizeof(typename Shape::Element);
      base_length_ += bytes;
      add(wire_type_name<typename Shape::Element>());
      add(" ");
      add(name);
      add(" ");
      if (Shape::kIsArray) crc_ = crc_accumulate(static_cast<uint8_t>(Shape::kCount), crc_);
    }
    max_length_ += bytes;
  }
  constexpr void extensions() { in_extensions_ = true; }

  constexpr size_t base_length() const { return base_length_; }
  constexpr size_t max_length() const { return max_length_; }
  constexpr bool wire_order_ok() const { return wire_order_ok_; }
  constexpr uint8_t crc_extra() const { return static_cast<uint8_t>((crc_ & 0xFF) ^ (crc_ >> 8)); }

 private:
  constexpr void add(std::string_view s) {
    for (char c : s) crc_ = crc_accumulate(static_cast<uint8_t>(c), crc_);
  }
  uint16_t crc_ = kCrcInit;
  size_t base_length_ = 0;
  size_t max_length_ = 0;
  size_t last_element_size_ = 8;
  bool in_extensions_ = false;
  bool wire_order_ok_ = true;
};

}  // namespace detail

/// Layout of message type M computed from its field list.
template <class M>
constexpr detail::LayoutVisitor layout_of() {
  detail::LayoutVisitor v(M::kName);
  M m{};
  M::fields(m, v);
  return v;
}

}  // namespace alight::mavlink
