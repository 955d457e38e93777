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

}  // namespace alight::autonomy
