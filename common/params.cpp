#include "common/params.hpp"

#include <filesystem>
#include <fstream>

namespace alight {

namespace {
std::string compose(const std::string& file, const std::string& key, const std::string& value,
                    const std::string& problem) {
  std::string msg = file.empty() ? std::string() : file + ": ";
  if (!key.empty()) msg += key + (value.empty() ? std::string() : " = " + value) + ": ";
  return msg + problem;
}

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
  std::ifstream in(path);
  if (!in) throw ParamError(path, "", "", "cannot open the file");
  std::stringstream text;
  text << in.rdbuf();
  return from_string(text.str(), path);
}

ParamNode ParamNode::from_string(const std::string& yaml, const std::string& name) {
  YAML::Node root;
  try {
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
