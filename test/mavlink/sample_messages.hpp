#pragma once
// Messages for the MAVLink tests, benchmarks and fuzz seeds: every field (extensions included)
// filled with its own pseudo-random value, never zero, so that a field read from the wrong
// offset, a swapped pair or a lost extension shows in any comparison.

#include <cmath>
#include <cstdint>
#include <string_view>
#include <type_traits>

#include "mavlink/messages.hpp"

namespace alight::mavlink::testing {

class DistinctFiller {
 public:
  explicit DistinctFiller(uint64_t seed) : state_(seed * 0x9E3779B97F4A7C15ull + 1) {}
  template <class T>
  void operator()(std::string_view, T& field) {
    using E = typename FieldShape<T>::Element;
    if constexpr (std::is_same_v<E, char>) {
      // Printable ASCII, JSON's escapes included.
      static constexpr std::string_view kChars =
          "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789 \"\\/:,.{}[]";
      for (char& c : field) c = kChars[next() % kChars.size()];
    } else if constexpr (FieldShape<T>::kIsArray) {
      for (E& e : field) set(e);
    } else {
      set(field);
    }
  }
  void extensions() {}

 private:
  uint64_t next() {  // splitmix64
    uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  template <class E>
  void set(E& v) {
    const uint64_t r = next();
    if constexpr (std::is_floating_point_v<E>) {
      // Magnitudes from 1e-4 to 1e4, both signs, never zero.
      const double mantissa = 1.0 + static_cast<double>(r >> 11) / 9007199254740992.0;
      const int exponent = static_cast<int>((r >> 3) % 28) - 14;
      v = static_cast<E>(((r & 1) ? -1.0 : 1.0) * std::ldexp(mantissa, exponent));
    } else if constexpr (std::is_signed_v<E>) {
      using U = std::make_unsigned_t<E>;
      auto u = static_cast<U>(r);
      if (u == 0) u = 1;
      v = static_cast<E>(u);  // both signs, extremes possible
    } else {
      v = static_cast<E>(r);
      if (v == 0) v = 1;
    }
  }
  uint64_t state_;
};

/// Zeroes the extension fields (so that MAVLink 2 truncates them away).
class ExtensionZeroer {
 public:
  template <class T>
  void operator()(std::string_view, T& field) {
    if (in_extensions_) field = T{};
  }
  void extensions() { in_extensions_ = true; }

 private:
  bool in_extensions_ = false;
};

/// Zeroes every field.
class Zeroer {
 public:
  template <class T>
  void operator()(std::string_view, T& field) {
    field = T{};
  }
  void extensions() {}
};

template <class M>
M distinct_message(uint64_t seed) {
  M m{};
  DistinctFiller f(seed * 1000 + M::kId);
  M::fields(m, f);
  return m;
}

template <class M>
M without_extensions(M m) {
  ExtensionZeroer z;
  M::fields(m, z);
  return m;
}

template <class M>
M zero_message() {
  M m{};
  Zeroer z;
  M::fields(m, z);
  return m;
}

}  // namespace alight::mavlink::testing
