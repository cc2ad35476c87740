#include "ehc_common/config_node.h"

#include <algorithm>
#include <map>
#include <sstream>

namespace ehc_common {

namespace {
std::string folderOf(const std::string& path) {
  const auto slash = path.find_last_of('/');
  return slash == std::string::npos ? std::string(".") : path.substr(0, slash);
}

std::string join(const std::string& field, const std::string& key) { return field.empty() ? key : field + "." + key; }

/// `over` (from `over_file`) merged onto a copy of `base`: mappings key by key, everything
/// else replaced; `origins` records the fields `over` set.
YAML::Node merged(const YAML::Node& base, const YAML::Node& over, const std::string& field,
                  const std::string& over_file, ConfigNode::Origins* origins) {
  if (!base.IsMap() || !over.IsMap()) {
    // The subtree is replaced whole: forget what its fields came from.
    for (const char* sep : {".", "["}) {
      const std::string prefix = field + sep;
      auto it = origins->lower_bound(prefix);
      while (it != origins->end() && it->first.compare(0, prefix.size(), prefix) == 0) it = origins->erase(it);
    }
    (*origins)[field] = over_file;
    return YAML::Clone(over);
  }
  YAML::Node out = YAML::Clone(base);
  for (const auto& kv : over) {
    const std::string key = kv.first.as<std::string>();
    const std::string f = join(field, key);
    if (out[key]) {
      out[key] = merged(out[key], kv.second, f, over_file, origins);
    } else {
      out[key] = YAML::Clone(kv.second);
      (*origins)[f] = over_file;
    }
  }
  return out;
}

YAML::Node loadWithExtends(const std::string& path, const std::string& owner, int depth, ConfigNode::Origins* origins) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw std::invalid_argument("[" + owner + "] cannot read config file '" + path + "'");
  } catch (const YAML::Exception& e) {
    throw std::invalid_argument("[" + owner + "] " + path + ": YAML syntax error: " + e.what());
  }
  if (!root.IsMap())
    throw std::invalid_argument("[" + owner + "] " + path + ": top level must be a mapping");
  if (!root["extends"]) {
    (*origins)[""] = path;
    return root;
  }
  if (depth >= 8)
    throw std::invalid_argument("[" + owner + "] " + path + ": 'extends' chain longer than 8 files (a cycle?)");
  if (!root["extends"].IsScalar())
    throw std::invalid_argument("[" + owner + "] " + path + ": field 'extends' must be a file name");
  std::string base = root["extends"].as<std::string>();
  if (!base.empty() && base[0] != '/') base = folderOf(path) + "/" + base;
  root.remove("extends");
  return merged(loadWithExtends(base, owner, depth + 1, origins), root, "", path, origins);
}

}  // namespace

ConfigNode ConfigNode::loadFile(const std::string& path, const std::string& owner) {
  auto origins = std::make_shared<Origins>();
  ConfigNode root(loadWithExtends(path, owner, 0, origins.get()), path, "", owner);
  root.origins_ = origins;
  return root;
}

ConfigNode ConfigNode::loadString(const std::string& text, const std::string& origin,
                                  const std::string& owner) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw std::invalid_argument("[" + owner + "] " + origin + ": YAML syntax error: " + e.what());
  }
  if (!root.IsMap())
    throw std::invalid_argument("[" + owner + "] " + origin + ": top level must be a mapping");
  return ConfigNode(root, origin, "", owner);
}

ConfigNode::ConfigNode(YAML::Node node, std::string file, std::string field, std::string owner)
    : node_(std::move(node)), file_(std::move(file)), field_(std::move(field)),
      owner_(std::move(owner)) {}

bool ConfigNode::has(const std::string& key) const {
  mark(key);
  return node_.IsMap() && node_[key] && !node_[key].IsNull();
}

YAML::Node ConfigNode::value(const std::string& key) const {
  if (!has(key)) fail(key, "is missing");
  return node_[key];
}

ConfigNode ConfigNode::child(const std::string& key) const {
  const YAML::Node n = value(key);
  if (!n.IsMap()) fail(key, "must be a mapping");
  return sub(n, fieldName(key));
}

ConfigNode ConfigNode::childOrEmpty(const std::string& key) const {
  if (!has(key)) return sub(YAML::Node(YAML::NodeType::Map), fieldName(key));
  return child(key);
}

ConfigNode ConfigNode::sub(const YAML::Node& n, const std::string& field) const {
  ConfigNode c(n, file_, field, owner_);
  c.usage_ = usage_;
  c.origins_ = origins_;
  return c;
}

std::size_t ConfigNode::listSize(const std::string& key) const {
  if (!has(key)) return 0;
  if (!node_[key].IsSequence()) fail(key, "must be a list");
  return node_[key].size();
}

ConfigNode ConfigNode::element(const std::string& key, std::size_t i) const {
  if (i >= listSize(key)) fail(key, "has no element " + std::to_string(i));
  const std::string field = fieldName(key) + "[" + std::to_string(i) + "]";
  const YAML::Node e = node_[key][i];
  if (!e.IsMap())
    throw std::invalid_argument("[" + owner_ + "] " + where(field) + ": field '" + field + "' must be a mapping");
  return sub(e, field);
}

std::vector<std::string> ConfigNode::keys() const {
  std::vector<std::string> out;
  if (!node_.IsMap()) return out;
  for (const auto& kv : node_) out.push_back(kv.first.as<std::string>());
  return out;
}

void ConfigNode::ignore(const std::string& key) const {
  mark(key);
  usage_->whole.insert(fieldName(key));
}

void ConfigNode::mark(const std::string& key) const { usage_->asked.insert(fieldName(key)); }

bool ConfigNode::used(const std::string& field) const {
  if (usage_->asked.count(field)) return true;
  // Inside a subtree read whole (yaml(), ignore()): the subtree's root is a prefix.
  for (const auto& w : usage_->whole)
    if (w.empty() || field == w || (field.size() > w.size() && field.compare(0, w.size(), w) == 0 &&
                                    (field[w.size()] == '.' || field[w.size()] == '[')))
      return true;
  return false;
}

void ConfigNode::collectUnknown(const YAML::Node& n, const std::string& field,
                                std::vector<std::string>* out) const {
  if (n.IsMap()) {
    for (const auto& kv : n) {
      const std::string key = kv.first.as<std::string>();
      const std::string f = field.empty() ? key : field + "." + key;
      if (!used(f)) out->push_back(f);
      else collectUnknown(kv.second, f, out);
    }
  } else if (n.IsSequence()) {
    for (std::size_t i = 0; i < n.size(); ++i)
      collectUnknown(n[i], field + "[" + std::to_string(i) + "]", out);
  }
}

std::vector<std::string> ConfigNode::unknownKeys() const {
  std::vector<std::string> out;
  if (!used(field_) && !field_.empty()) return {field_};
  collectUnknown(node_, field_, &out);
  return out;
}

namespace {
std::size_t editDistance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diag = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diag = up;
    }
  }
  return row[b.size()];
}
std::string parentOf(const std::string& field) {
  const auto dot = field.find_last_of('.');
  return dot == std::string::npos ? std::string() : field.substr(0, dot);
}
}  // namespace

void ConfigNode::rejectUnknownKeys() const {
  const std::vector<std::string> unknown = unknownKeys();
  if (unknown.empty()) return;
  const std::string& f = unknown.front();
  // Nearest key a loader asked for in the same mapping.
  std::string best;
  std::size_t best_d = 4;
  const std::string parent = parentOf(f);
  const std::string leaf = parent.empty() ? f : f.substr(parent.size() + 1);
  for (const auto& a : usage_->asked) {
    if (parentOf(a) != parent) continue;
    const std::string a_leaf = parent.empty() ? a : a.substr(parent.size() + 1);
    const std::size_t d = editDistance(leaf, a_leaf);
    if (d < best_d || (d == best_d && !best.empty() && a < best)) {
      best_d = d;
      best = a;
    }
  }
  std::ostringstream os;
  os << "[" << owner_ << "] " << where(f) << ": unknown field '" << f << "'";
  if (!best.empty()) os << " (did you mean '" << best << "'?)";
  else os << " (no parameter of that name is read here)";
  if (unknown.size() > 1) {
    os << "; also unknown:";
    for (std::size_t i = 1; i < unknown.size(); ++i) os << " '" << unknown[i] << "'";
  }
  throw std::invalid_argument(os.str());
}

Eigen::VectorXd ConfigNode::getVector(const std::string& key, const Eigen::VectorXd& fallback,
                                      int expected_size) const {
  if (!has(key)) return fallback;
  return requireVector(key, expected_size);
}

Eigen::VectorXd ConfigNode::requireVector(const std::string& key, int expected_size) const {
  const YAML::Node n = value(key);
  if (!n.IsSequence()) fail(key, "must be a list of numbers");
  if (expected_size >= 0 && static_cast<int>(n.size()) != expected_size)
    fail(key, "must have " + std::to_string(expected_size) + " elements (has " +
                  std::to_string(n.size()) + ")");
  Eigen::VectorXd v(n.size());
  for (std::size_t i = 0; i < n.size(); ++i) {
    try {
      v[static_cast<int>(i)] = n[i].as<double>();
    } catch (const YAML::Exception&) {
      fail(key, "element " + std::to_string(i) + " is not a number ('" + dump(n[i]) + "')");
    }
    if (!std::isfinite(v[static_cast<int>(i)]))
      fail(key, "element " + std::to_string(i) + " must be finite");
  }
  return v;
}

std::vector<std::string> ConfigNode::getStrings(const std::string& key,
                                                const std::vector<std::string>& fallback) const {
  if (!has(key)) return fallback;
  const YAML::Node n = value(key);
  if (!n.IsSequence()) fail(key, "must be a list of strings");
  std::vector<std::string> out;
  for (const auto& e : n) {
    if (!e.IsScalar()) fail(key, "must be a list of strings");
    out.push_back(e.as<std::string>());
  }
  return out;
}

void ConfigNode::fail(const std::string& key, const std::string& what) const {
  throw std::invalid_argument("[" + owner_ + "] " + where(fieldName(key)) + ": field '" + fieldName(key) + "' " +
                              what);
}

std::string ConfigNode::originOf(const std::string& field) const {
  if (!origins_) return file_;
  std::string f = field;
  for (;;) {
    const auto it = origins_->find(f);
    if (it != origins_->end()) return it->second;
    if (f.empty()) return file_;
    const auto cut = f.find_last_of(".[");
    f = cut == std::string::npos ? std::string() : f.substr(0, cut);
  }
}

std::string ConfigNode::where(const std::string& field) const {
  const std::string origin = originOf(field);
  return origin == file_ ? file_ : origin + " (through 'extends' of " + file_ + ")";
}

std::string ConfigNode::fileChain() const {
  std::string bases;
  if (origins_)
    for (const auto& kv : *origins_)
      if (kv.second != file_ && bases.find("'" + kv.second + "'") == std::string::npos)
        bases += (bases.empty() ? "'" : ", '") + kv.second + "'";
  return bases.empty() ? file_ : file_ + " (extends " + bases + ")";
}

std::string ConfigNode::fileOf(const std::string& key) const { return originOf(fieldName(key)); }

std::string ConfigNode::requirePath(const std::string& key) const {
  const std::string value = require<std::string>(key);
  if (value.empty()) fail(key, "must not be empty (a file path)");
  if (value[0] == '/') return value;
  return folderOf(fileOf(key)) + "/" + value;
}

std::string ConfigNode::getPath(const std::string& key, const std::string& fallback) const {
  return has(key) ? requirePath(key) : fallback;
}

std::string ConfigNode::fieldName(const std::string& key) const {
  if (key.empty()) return field_;
  return field_.empty() ? key : field_ + "." + key;
}

std::string ConfigNode::dump(const YAML::Node& n) {
  std::ostringstream os;
  os << n;
  return os.str();
}

void requireRange(const std::string& owner, const std::string& field, double value, double lo,
                  double hi) {
  if (!std::isfinite(value) || value < lo || value > hi) {
    std::ostringstream os;
    os << "[" << owner << "] parameter '" << field << "' = " << value << " is outside [" << lo
       << ", " << hi << "]";
    throw std::invalid_argument(os.str());
  }
}

void requirePositive(const std::string& owner, const std::string& field, double value) {
  if (!std::isfinite(value) || value <= 0.0) {
    std::ostringstream os;
    os << "[" << owner << "] parameter '" << field << "' = " << value << " must be > 0";
    throw std::invalid_argument(os.str());
  }
}

}  // namespace ehc_common
