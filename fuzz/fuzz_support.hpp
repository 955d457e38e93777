#pragma once
// Shared pieces of the libFuzzer targets in fuzz/ (see fuzz/README.md). Each target feeds one
// kind of untrusted input through the code a process runs on it; the sanitizers (ASan, UBSan
// with -fno-sanitize-recover) and the checks below turn any misbehaviour into a crash that
// libFuzzer saves as a reproducer.

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <type_traits>

#include "common/build_paths.hpp"
#include "common/decode.hpp"
#include "common/params.hpp"

namespace alight::fuzz {

/// Aborts (a crash libFuzzer records) with a message saying which property was broken.
[[noreturn]] inline void fail(const std::string& what) {
  std::fprintf(stderr, "alight fuzz: %s\n", what.c_str());
  std::fflush(stderr);
  std::abort();
}

/// Decodes through the nodes' decoder (never throws).
template <class Msg>
std::optional<Msg> decode(const uint8_t* data, size_t size) {
  Msg msg{};
  if (!decode_message(msg, data, size)) return std::nullopt;
  return msg;
}

/// A conversion may return the value itself or an optional (the validating forms): a pointer to
/// the value, or nullptr when it was refused.
template <class T>
struct is_optional : std::false_type {};
template <class T>
struct is_optional<std::optional<T>> : std::true_type {};
template <class T>
auto* value_of(T& v) {
  if constexpr (is_optional<T>::value) {
    return v ? &*v : nullptr;
  } else {
    return &v;
  }
}

/// Runs a configuration loader. A bad file must be a ParamError (exit 2 naming file, key and
/// value; docs/ARCHITECTURE.md "Errors: three tiers"); anything else escaping a loader
/// (yaml-cpp's exceptions, std::out_of_range, ...) would end the node with exit 1 and a message
/// that names no key, so it counts as a crash.
template <class F>
void expect_param_errors_only(const char* loader, F&& f) {
  try {
    f();
  } catch (const ParamError&) {
  } catch (const std::exception& e) {
    fail(std::string(loader) + " threw a non-ParamError exception: " + e.what());
  }
}

/// The input as a file, for loaders that take a path: <dir>/<subdir>/input.yaml in a directory
/// of this process, next to a link <dir>/cameras -> config/cameras and links to its files in
/// <subdir>, so that relative names as the repository's files use them
/// ("../cameras/firefly_mv_4mm.yaml", "firefly_mv_4mm.yaml") resolve and the loaders' later
/// stages run. In /dev/shm when there is one: the fuzzer rewrites it for every input.
class InputFile {
 public:
  explicit InputFile(const std::string& subdir) {
    const char* env = std::getenv("ALIGHT_FUZZ_TMPDIR");
    const std::string base = env ? env : (access("/dev/shm", W_OK) == 0 ? "/dev/shm" : "/tmp");
    dir_ = base + "/alight-fuzz-" + std::to_string(getpid());
    std::filesystem::create_directories(dir_ + "/" + subdir);
    std::error_code ec;
    const std::filesystem::path cameras =
        std::string(alight::build::source_dir()) + "/config/cameras";
    std::filesystem::create_directory_symlink(cameras, dir_ + "/cameras", ec);
    for (const auto& f : std::filesystem::directory_iterator(cameras, ec))
      std::filesystem::create_symlink(f.path(),
                                      dir_ + "/" + subdir + "/" + f.path().filename().string(), ec);
    path_ = dir_ + "/" + subdir + "/input.yaml";
  }
  ~InputFile() {
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
  }
  const std::string& write(const uint8_t* data, size_t size) {
    std::ofstream f(path_, std::ios::binary | std::ios::trunc);
    f.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
    return path_;
  }
  const std::string& path() const { return path_; }

 private:
  std::string dir_, path_;
};

}  // namespace alight::fuzz
