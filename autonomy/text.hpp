#pragma once
// Numbers in the status reasons of the autonomy (fixed notation, so that reasons compare).

#include <sstream>
#include <string>

namespace alight::autonomy {

inline std::string fmt(double v, int precision = 3) {
  std::ostringstream os;
  os.setf(std::ios::fixed);
  os.precision(precision);
  os << v;
  return os.str();
}

/// A reason with each of its numbers written as '#': what it says, not how much. A reason that
/// carries a measured offset changes with every step (a moving platform's follow, 200 times a
/// second); the node logs a reason when this changes.
inline std::string reason_kind(const std::string& reason) {
  std::string out;
  out.reserve(reason.size());
  for (size_t i = 0; i < reason.size(); ++i) {
    const char c = reason[i];
    const bool digit = c >= '0' && c <= '9';
    // A sign or a point belongs to a number when a digit follows it.
    const bool lead = (c == '-' || c == '+' || c == '.') && i + 1 < reason.size() &&
                      reason[i + 1] >= '0' && reason[i + 1] <= '9';
    if (digit || lead) {
      if (out.empty() || out.back() != '#') out.push_back('#');
    } else {
      out.push_back(c);
    }
  }
  return out;
}

}  // namespace alight::autonomy
