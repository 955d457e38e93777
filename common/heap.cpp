#include "common/heap.hpp"

#include <cstdlib>  // defines __GLIBC__ on glibc (the check below needs a libc header first)

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace alight {

bool retain_freed_memory() {
#if defined(__GLIBC__)
  // glibc caps M_MMAP_THRESHOLD at 32 MiB on 64-bit (DEFAULT_MMAP_THRESHOLD_MAX).
  const bool mmap_ok = mallopt(M_MMAP_THRESHOLD, 32 * 1024 * 1024) == 1;
  const bool trim_ok = mallopt(M_TRIM_THRESHOLD, 512 * 1024 * 1024) == 1;
  return mmap_ok && trim_ok;
#else
  return true;
#endif
}

}  // namespace alight
