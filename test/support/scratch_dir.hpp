#pragma once
// A folder of the test process's own for the files its tests write (keys, logs, configs, state
// files): created on first use in the system's temporary folder, removed with all it holds when
// the process exits, so that a run leaves nothing behind there (a key file least of all) and two
// processes never share a file.

#include <stdlib.h>

#include <filesystem>
#include <stdexcept>
#include <string>

namespace alight::test {

inline const std::filesystem::path& scratch_dir() {
  struct Dir {
    std::filesystem::path path;
    Dir() {
      std::string pattern =
          (std::filesystem::temp_directory_path() / "alight-test-XXXXXX").string();
      if (!mkdtemp(pattern.data()))
        throw std::runtime_error("cannot create a scratch folder like " + pattern);
      path = pattern;
    }
    ~Dir() {
      std::error_code ignored;  // at exit: nothing left to report it to
      std::filesystem::remove_all(path, ignored);
    }
  };
  static const Dir dir;
  return dir.path;
}

/// `name` in the process's scratch folder.
inline std::string scratch_path(const std::string& name) { return (scratch_dir() / name).string(); }

}  // namespace alight::test
