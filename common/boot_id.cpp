#include "common/boot_id.hpp"

#include <fstream>

namespace alight {

std::string read_boot_id() {
  std::ifstream in("/proc/sys/kernel/random/boot_id");
  std::string id;
  std::getline(in, id);
  return id;
}

}  // namespace alight
