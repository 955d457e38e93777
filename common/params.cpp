#include "common/params.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <yaml-cpp/eventhandler.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <filesystem>

namespace alight {

namespace {
std::string compose(const std::string& file, const std::string& key, const std::string& value,
                    const std::string& problem) {
  std::string msg = file.empty() ? std::string() : file + ": ";
  if (!key.empty()) msg += key + (value.empty() ? std::string() : " = " + value) + ": ";
  return msg + problem;
}

std::string file_kind(mode_t mode) {
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "a special file";
}

std::string size_text(size_t bytes) {
  return bytes % (1 << 20) == 0 ? std::to_string(bytes >> 20) + " MiB"
                                : std::to_string(bytes) + " bytes";
}

// A FIFO without a writer blocks its reader for good, a device can stream without end: only a
// regular file has a known, bounded length.
void check_regular(const std::string& path, const struct stat& st, size_t max_bytes) {
  if (!S_ISREG(st.st_mode))
    throw ParamError(path, "", "", "not a regular file (" + file_kind(st.st_mode) + ")");
  if (static_cast<uint64_t>(st.st_size) > max_bytes)
    throw ParamError(path, "", "",
                     "file too large: " + std::to_string(st.st_size) + " bytes, at most " +
                         size_text(max_bytes));
}

// The file's text. stat() first, so that a device is never opened (opening a serial port can
// reset the board on it, a tape rewinds); O_NONBLOCK, so that a FIFO swapped in after the stat
// cannot block the open; fstat() of what was opened, which is what gets read.
std::string read_bounded(const std::string& path, size_t max_bytes) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0)
    throw ParamError(path, "", "", std::string("cannot open the file: ") + std::strerror(errno));
  check_regular(path, st, max_bytes);
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK | O_NOCTTY);
  if (fd < 0)
    throw ParamError(path, "", "", std::string("cannot open the file: ") + std::strerror(errno));
  std::string text;
  try {
    if (::fstat(fd, &st) != 0)
      throw ParamError(path, "", "", std::string("cannot stat the file: ") + std::strerror(errno));
    check_regular(path, st, max_bytes);
    // One byte beyond the limit tells a file that grew since the fstat from one that fits.
    text.resize(max_bytes + 1);
    size_t n = 0;
    while (n < text.size()) {
      const ssize_t r = ::read(fd, text.data() + n, text.size() - n);
      if (r < 0 && errno == EINTR) continue;
      if (r < 0)
        throw ParamError(path, "", "",
                         std::string("cannot read the file: ") + std::strerror(errno));
      if (r == 0) break;
      n += static_cast<size_t>(r);
    }
    if (n > max_bytes)
      throw ParamError(path, "", "", "file too large: more than " + size_text(max_bytes));
    text.resize(n);
  } catch (...) {
    ::close(fd);
    throw;
  }
  ::close(fd);
  return text;
}

// A first pass over the parser's events, before any tree is built: refuses aliases and anchors
// and bounds the node count and the nesting, each at the line where the limit is crossed.
class StructureCheck : public YAML::EventHandler {
 public:
  explicit StructureCheck(std::string name) : name_(std::move(name)) {}

  void OnDocumentStart(const YAML::Mark&) override {}
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark& mark, YAML::anchor_t anchor) override { node(mark, anchor); }
  void OnAlias(const YAML::Mark& mark, YAML::anchor_t) override {
    refuse(mark, "YAML aliases (*name) are not accepted in parameter files: write the values out");
  }
  void OnScalar(const YAML::Mark& mark, const std::string&, YAML::anchor_t anchor,
                const std::string&) override {
    node(mark, anchor);
  }
  void OnSequenceStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t anchor,
                       YAML::EmitterStyle::value) override {
    open(mark, anchor);
  }
  void OnSequenceEnd() override { --depth_; }
  void OnMapStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t anchor,
                  YAML::EmitterStyle::value) override {
    open(mark, anchor);
  }
  void OnMapEnd() override { --depth_; }

 private:
  void node(const YAML::Mark& mark, YAML::anchor_t anchor) {
    if (anchor != YAML::NullAnchor)
      refuse(mark,
             "YAML anchors (&name) are not accepted in parameter files: write the values "
             "out");
    if (++nodes_ > ParamNode::kMaxNodes)
      refuse(mark, "more than " + std::to_string(ParamNode::kMaxNodes) + " values");
  }
  void open(const YAML::Mark& mark, YAML::anchor_t anchor) {
    node(mark, anchor);
    if (++depth_ > ParamNode::kMaxDepth)
      refuse(mark, "nested deeper than " + std::to_string(ParamNode::kMaxDepth) + " levels");
  }
  [[noreturn]] void refuse(const YAML::Mark& mark, const std::string& problem) const {
    throw ParamError(name_, "", "", "line " + std::to_string(mark.line + 1) + ": " + problem);
  }

  std::string name_;
  size_t nodes_ = 0;
  int depth_ = 0;
};

// Walks every mapping and sequence; `path` is the dotted key of `node`.
void reject_duplicate_keys(const YAML::Node& node, const std::string& path,
                           const std::string& file) {
  if (node.IsMap()) {
    std::set<std::string> seen;
    for (const auto& kv : node) {
      const std::string key =
          kv.first.IsScalar() ? kv.first.Scalar() : std::string("<complex key>");
      const std::string full = path.empty() ? key : path + "." + key;
      if (!seen.insert(key).second)
        throw ParamError(file, full, kv.second.IsScalar() ? kv.second.Scalar() : "",
                         "duplicate key (line " + std::to_string(kv.first.Mark().line + 1) +
                             "): the key appears twice in the same mapping");
      reject_duplicate_keys(kv.second, full, file);
    }
  } else if (node.IsSequence()) {
    for (size_t i = 0; i < node.size(); ++i)
      reject_duplicate_keys(node[i], path + "[" + std::to_string(i) + "]", file);
  }
}
}  // namespace

std::string resolve_relative(const std::string& relative_to_file, const std::string& path) {
  const std::filesystem::path p(path);
  if (p.is_absolute()) return path;
  return (std::filesystem::path(relative_to_file).parent_path() / p).lexically_normal().string();
}

ParamError::ParamError(std::string file, std::string key, std::string value, std::string problem)
    : std::runtime_error(compose(file, key, value, problem)),
      file_(std::move(file)),
      key_(std::move(key)),
      value_(std::move(value)),
      problem_(std::move(problem)) {}

ParamError ParamError::located(const std::string& file, const std::string& key_prefix) const {
  const std::string key =
      key_prefix.empty() ? key_ : (key_.empty() ? key_prefix : key_prefix + "." + key_);
  return ParamError(file_.empty() ? file : file_, key, value_, problem_);
}

ParamNode::ParamNode(std::shared_ptr<const std::string> file, YAML::Node node, std::string path)
    : file_(std::move(file)),
      node_(std::move(node)),
      path_(std::move(path)),
      read_keys_(std::make_shared<std::set<std::string>>()) {}

ParamNode ParamNode::load_file(const std::string& path) {
  return from_string(read_bounded(path, kMaxFileBytes), path);
}

ParamNode ParamNode::from_string(const std::string& yaml, const std::string& name) {
  if (yaml.size() > kMaxFileBytes)
    throw ParamError(name, "", "",
                     "too large: " + std::to_string(yaml.size()) + " bytes, at most " +
                         size_text(kMaxFileBytes));
  YAML::Node root;
  try {
    std::istringstream in(yaml);
    YAML::Parser parser(in);
    StructureCheck check(name);
    parser.HandleNextDocument(check);
    root = YAML::Load(yaml);
  } catch (const YAML::Exception& e) {
    throw ParamError(name, "", "",
                     "invalid YAML at line " + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
  if (!root.IsMap()) throw ParamError(name, "", "", "the top level must be a mapping of keys");
  reject_duplicate_keys(root, "", name);
  return ParamNode(std::make_shared<const std::string>(name), root, "");
}

bool ParamNode::has(const std::string& key) const {
  return node_.IsMap() && node_[key].IsDefined() && !node_[key].IsNull();
}

YAML::Node ParamNode::at(const std::string& key) const {
  read_keys_->insert(key);
  return node_[key];
}

std::string ParamNode::value_text(const std::string& key) const {
  if (!node_.IsMap() || !node_[key].IsDefined()) return "<missing>";
  const YAML::Node n = node_[key];
  if (n.IsScalar()) return n.Scalar();
  YAML::Emitter out;
  out << YAML::Flow << n;
  return out.c_str();
}

ParamError ParamNode::error(const std::string& key, const std::string& value,
                            const std::string& problem) const {
  return ParamError(*file_, key_path(key), value, problem);
}

void ParamNode::check(bool ok, const std::string& key, const std::string& problem) const {
  if (!ok) throw error(key, value_text(key), problem);
}

ParamNode ParamNode::child(const std::string& key) const {
  if (!has(key)) throw error(key, "<missing>", "required section is missing");
  const YAML::Node n = at(key);
  if (!n.IsMap()) throw error(key, value_text(key), "expected a mapping of keys");
  return ParamNode(file_, n, key_path(key));
}

std::optional<ParamNode> ParamNode::optional_child(const std::string& key) const {
  if (!has(key)) {
    read_keys_->insert(key);
    return std::nullopt;
  }
  return child(key);
}

std::vector<ParamNode> ParamNode::child_list(const std::string& key) const {
  if (!has(key)) throw error(key, "<missing>", "required list is missing");
  const YAML::Node n = at(key);
  if (!n.IsSequence()) throw error(key, value_text(key), "expected a list");
  std::vector<ParamNode> out;
  for (size_t i = 0; i < n.size(); ++i) {
    const std::string item = key_path(key) + "[" + std::to_string(i) + "]";
    if (!n[i].IsMap()) throw ParamError(*file_, item, "", "expected a mapping of keys");
    out.push_back(ParamNode(file_, n[i], item));
  }
  return out;
}

void ParamNode::finish(const std::vector<std::string>& ignored) const {
  if (!node_.IsMap()) return;
  for (const auto& kv : node_) {
    // A key that is a list or a mapping ({[a]: 1}) is nobody's parameter; found by fuzzing, it
    // threw yaml-cpp's BadConversion, and the node exited 1 naming nothing.
    if (!kv.first.IsScalar())
      throw ParamError(
          *file_,
          key_path("<" + std::string(kv.first.IsSequence() ? "list" : "mapping") + " as a key>"),
          "", "keys must be plain names (line " + std::to_string(kv.first.Mark().line + 1) + ")");
    const std::string key = kv.first.Scalar();
    if (read_keys_->count(key)) continue;
    bool skip = false;
    for (const auto& i : ignored) skip = skip || i == key;
    if (!skip) throw error(key, value_text(key), "unknown key (misspelt, or not used here)");
  }
}

}  // namespace alight
