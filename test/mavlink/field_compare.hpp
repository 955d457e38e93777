#pragma once
// Field-by-field comparison of an alight message with the values a peer printed as JSON (read
// with yaml-cpp: JSON is YAML's flow style). Numbers are compared exactly: integers as decimal
// text (64-bit ones arrive as strings), floats bit for bit after parsing the peer's shortest
// round-trip text ("NaN", "Infinity", "-Infinity", "-0" as strings), char arrays as text up to
// the first NUL.

#include <yaml-cpp/yaml.h>

#include <array>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <sstream>
#include <string>
#include <string_view>
#include <type_traits>

#include "mavlink/wire.hpp"

namespace alight::mavlink::testing {

class JsonFieldCompare {
 public:
  explicit JsonFieldCompare(const YAML::Node& fields) : fields_(fields) {}

  template <class T>
  void operator()(std::string_view name_view, const T& field) {
    const std::string name(name_view);
    ++compared_;
    const YAML::Node v = fields_[name];
    if (!v) {
      diff(name, "missing from the peer's output");
      return;
    }
    using Shape = FieldShape<T>;
    using E = typename Shape::Element;
    if constexpr (std::is_same_v<E, char>) {
      std::string ours;
      for (char c : field) {
        if (c == '\0') break;
        ours += c;
      }
      const std::string theirs = v.as<std::string>();
      if (ours != theirs) diff(name, "\"" + theirs + "\" != ours \"" + ours + "\"");
    } else if constexpr (Shape::kIsArray) {
      if (!v.IsSequence() || v.size() != Shape::kCount) {
        diff(name, "not an array of " + std::to_string(Shape::kCount));
        return;
      }
      for (size_t i = 0; i < Shape::kCount; ++i)
        scalar(name + "[" + std::to_string(i) + "]", v[i], field[i]);
    } else {
      scalar(name, v, field);
    }
  }
  void extensions() {}

  /// Differences found, one per line; empty when every field matched.
  const std::string& differences() const { return diffs_; }
  int compared() const { return compared_; }

 private:
  template <class E>
  void scalar(const std::string& name, const YAML::Node& v, E ours) {
    if (!v.IsScalar()) {
      diff(name, "not a scalar");
      return;
    }
    const std::string text = v.as<std::string>();
    char* end = nullptr;
    errno = 0;
    bool equal = false;
    std::ostringstream ours_text;
    if constexpr (std::is_floating_point_v<E>) {
      const E theirs = static_cast<E>(std::strtod(text.c_str(), &end));
      equal = (std::isnan(theirs) && std::isnan(ours)) ||
              std::bit_cast<std::array<uint8_t, sizeof(E)>>(theirs) ==
                  std::bit_cast<std::array<uint8_t, sizeof(E)>>(ours);
      ours_text.precision(17);
      ours_text << ours;
    } else if constexpr (std::is_signed_v<E>) {
      const long long theirs = std::strtoll(text.c_str(), &end, 10);
      equal = theirs == static_cast<long long>(ours);
      ours_text << static_cast<long long>(ours);
    } else {
      const unsigned long long theirs = std::strtoull(text.c_str(), &end, 10);
      equal =
          text.find('-') == std::string::npos && theirs == static_cast<unsigned long long>(ours);
      ours_text << static_cast<unsigned long long>(ours);
    }
    if (end == text.c_str() || *end != '\0' || errno == ERANGE) {
      diff(name, "\"" + text + "\" is not a number");
    } else if (!equal) {
      diff(name, text + " != ours " + ours_text.str());
    }
  }
  void diff(const std::string& name, const std::string& what) {
    diffs_ += "  " + name + ": " + what + "\n";
  }

  YAML::Node fields_;
  std::string diffs_;
  int compared_ = 0;
};

/// Differences between `m` and the peer's JSON fields; empty when equal. Also demands that the
/// peer printed exactly as many fields as `m` has.
template <class M>
std::string compare_fields(const M& m, const YAML::Node& fields) {
  JsonFieldCompare c(fields);
  M::fields(m, c);
  std::string out = c.differences();
  if (fields.IsMap() && static_cast<int>(fields.size()) != c.compared())
    out += "  the peer printed " + std::to_string(fields.size()) + " fields, alight has " +
           std::to_string(c.compared()) + "\n";
  return out;
}

}  // namespace alight::mavlink::testing
