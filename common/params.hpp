#pragma once
// Parameter loading: YAML files into per-component parameter structs, with every error naming
// the file, the dotted key and the offending value ("config/vehicles/pelican.yaml:
// autonomy.refinement.n_min = -3: must be >= 1"). Only nodes load files; libraries receive the
// filled structs.

#include <yaml-cpp/yaml.h>

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <cstddef>
#include <memory>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace alight {

/// Bad configuration from outside: names where (file, key) and what (value, problem).
class ParamError : public std::runtime_error {
 public:
  ParamError(std::string file, std::string key, std::string value, std::string problem);

  const std::string& file() const { return file_; }
  const std::string& key() const { return key_; }
  const std::string& value() const { return value_; }
  const std::string& problem() const { return problem_; }

  /// The same error, located in `file` with `key_prefix` prepended to the key (used when a
  /// struct's validate(), which knows neither, threw it).
  ParamError located(const std::string& file, const std::string& key_prefix) const;

 private:
  std::string file_, key_, value_, problem_;
};

/// Resolves `path` relative to the folder of `relative_to_file` unless it is absolute.
std::string resolve_relative(const std::string& relative_to_file, const std::string& path);

/// Throws ParamError (without file) when `ok` is false; for validate() methods.
template <class T>
void param_check(bool ok, const std::string& key, const T& value, const std::string& problem) {
  if (!ok) {
    std::ostringstream os;
    os << value;
    throw ParamError("", key, os.str(), problem);
  }
}

/// One YAML mapping of a parameter file, with the file name and the dotted path to it. Reads
/// typed values into fields that already hold their defaults; an absent optional key keeps the
/// default, a present key of the wrong type is an error. `finish()` rejects keys nobody read, so
/// a typo never silently leaves a default in place.
class ParamNode {
 public:
  /// Limits on what a parameter file may be, so that no file can hang or exhaust a node: it is
  /// read whole, parsed into a tree and walked, all before the node starts. The largest shipped
  /// file (a vehicle) is 13 kB, 370 values (keys count) and 5 levels deep.
  static constexpr size_t kMaxFileBytes = 1 << 20;
  /// Scalars (keys too), mappings and lists. yaml-cpp builds 500,000 of them, 1 MiB of
  /// `[0,0,...]`, in 0.7 s and 240 MB; 100,000 take 50 MB.
  static constexpr size_t kMaxNodes = 100'000;
  /// Nesting of mappings and lists (the top level is 1); yaml-cpp parses, copies and frees a
  /// tree by recursion, as does the duplicate-key check.
  static constexpr int kMaxDepth = 32;

  /// Loads a YAML file whose top level must be a mapping. Throws ParamError naming the file when
  /// it is missing or unreadable, not a regular file (a FIFO, a device: reading either can block
  /// forever or never end), larger than kMaxFileBytes, or when its text fails from_string.
  static ParamNode load_file(const std::string& path);
  /// Parses YAML text; `name` stands in for the file name in errors. Refuses text longer than
  /// kMaxFileBytes, invalid YAML, anchors and aliases (&a, *a, and so `<<: *a`: an alias shares
  /// a node, so a few hundred bytes of nested aliases expand to billions of values when walked
  /// or printed; no parameter file needs them), more than kMaxNodes nodes, nesting deeper than
  /// kMaxDepth, and a mapping anywhere that repeats a key (yaml-cpp keeps both and lookups see
  /// the first: a later edit would silently do nothing).
  static ParamNode from_string(const std::string& yaml, const std::string& name = "<string>");

  const std::string& file() const { return *file_; }
  const std::string& path() const { return path_; }
  std::string key_path(const std::string& key) const {
    return path_.empty() ? key : path_ + "." + key;
  }
  bool has(const std::string& key) const;
  const YAML::Node& yaml() const { return node_; }

  /// Required sub-mapping.
  ParamNode child(const std::string& key) const;
  /// Sub-mapping if present.
  std::optional<ParamNode> optional_child(const std::string& key) const;
  /// Elements of a required sequence of mappings (e.g. a list of processes).
  std::vector<ParamNode> child_list(const std::string& key) const;

  /// Reads `key` into `field` if present (keeps the default otherwise).
  template <class T>
  void read(const std::string& key, T& field) const {
    if (has(key)) field = get<T>(key);
  }
  /// Reads `key`, which must be present.
  template <class T>
  void require(const std::string& key, T& field) const {
    if (!has(key)) throw error(key, "<missing>", "required key is missing");
    field = get<T>(key);
  }
  /// Converts the value at `key` (present) to T.
  template <class T>
  T get(const std::string& key) const;

  /// Throws a ParamError naming `key` and its current value in this file when !ok.
  void check(bool ok, const std::string& key, const std::string& problem) const;
  ParamError error(const std::string& key, const std::string& value,
                   const std::string& problem) const;
  /// Runs a struct's validate() and locates any ParamError it throws in this file and section.
  template <class P>
  void validate(const P& params) const {
    try {
      params.validate();
    } catch (const ParamError& e) {
      throw e.located(file(), path_);
    }
  }
  /// Throws on any key of this mapping that was never read (typos, stale keys). `ignored` lists
  /// keys that belong to other components sharing the file.
  void finish(const std::vector<std::string>& ignored = {}) const;

  std::string value_text(const std::string& key) const;

 private:
  ParamNode(std::shared_ptr<const std::string> file, YAML::Node node, std::string path);
  YAML::Node at(const std::string& key) const;  // marks the key as read

  std::shared_ptr<const std::string> file_;
  YAML::Node node_;
  std::string path_;
  std::shared_ptr<std::set<std::string>> read_keys_;
};

namespace detail {
template <class T>
struct ParamConvert {
  static T from(const YAML::Node& n) { return n.as<T>(); }
  static const char* expected() { return "a value of the expected type"; }
};
template <>
struct ParamConvert<bool> {
  static bool from(const YAML::Node& n) { return n.as<bool>(); }
  static const char* expected() { return "true or false"; }
};
template <>
struct ParamConvert<int> {
  static int from(const YAML::Node& n) { return n.as<int>(); }
  static const char* expected() { return "an integer"; }
};
template <>
struct ParamConvert<int64_t> {
  static int64_t from(const YAML::Node& n) { return n.as<int64_t>(); }
  static const char* expected() { return "an integer"; }
};
// Non-finite numbers (.inf, .nan) are never a valid setting: an infinite timeout turns a
// failsafe off, a NaN gain poisons a controller.
template <>
struct ParamConvert<uint64_t> {  // seeds
  static uint64_t from(const YAML::Node& n) {
    const int64_t v = n.as<int64_t>();
    if (v < 0) throw YAML::BadConversion(n.Mark());
    return static_cast<uint64_t>(v);
  }
  static const char* expected() { return "a non-negative integer"; }
};
template <>
struct ParamConvert<double> {
  static double from(const YAML::Node& n) {
    const double v = n.as<double>();
    if (!std::isfinite(v)) throw YAML::BadConversion(n.Mark());
    return v;
  }
  static const char* expected() { return "a finite number"; }
};
template <>
struct ParamConvert<std::string> {
  static std::string from(const YAML::Node& n) {
    if (!n.IsScalar()) throw YAML::BadConversion(n.Mark());
    return n.as<std::string>();
  }
  static const char* expected() { return "a string"; }
};
template <class E, size_t N>
struct ParamConvert<std::array<E, N>> {
  static std::array<E, N> from(const YAML::Node& n) {
    if (!n.IsSequence() || n.size() != N) throw YAML::BadConversion(n.Mark());
    std::array<E, N> out{};
    for (size_t i = 0; i < N; ++i) out[i] = ParamConvert<E>::from(n[i]);
    return out;
  }
  static std::string expected() { return "a list of " + std::to_string(N) + " finite numbers"; }
};
template <class E>
struct ParamConvert<std::vector<E>> {
  static std::vector<E> from(const YAML::Node& n) {
    if (!n.IsSequence()) throw YAML::BadConversion(n.Mark());
    std::vector<E> out;
    for (const auto& e : n) out.push_back(ParamConvert<E>::from(e));
    return out;
  }
  static const char* expected() { return "a list"; }
};
template <>
struct ParamConvert<Eigen::Vector3d> {
  static Eigen::Vector3d from(const YAML::Node& n) {
    const auto a = ParamConvert<std::array<double, 3>>::from(n);
    return Eigen::Vector3d(a[0], a[1], a[2]);
  }
  static const char* expected() { return "a list of 3 finite numbers"; }
};
template <>
struct ParamConvert<Eigen::Vector2d> {
  static Eigen::Vector2d from(const YAML::Node& n) {
    const auto a = ParamConvert<std::array<double, 2>>::from(n);
    return Eigen::Vector2d(a[0], a[1]);
  }
  static const char* expected() { return "a list of 2 finite numbers"; }
};
}  // namespace detail

template <class T>
T ParamNode::get(const std::string& key) const {
  const YAML::Node n = at(key);
  try {
    return detail::ParamConvert<T>::from(n);
  } catch (const YAML::Exception&) {
    throw error(key, value_text(key),
                std::string("expected ") + detail::ParamConvert<T>::expected());
  }
}

}  // namespace alight
