#pragma once
// ConfigNode: a read-only view of a YAML document that names the file and the field in every
// error, so that a bad configuration fails at start-up with a message a user can act on.
// ROS-free (yaml-cpp only); used by every package's parameter loaders.
//
// Unknown keys are errors: every node made from one loaded document shares a record of the
// keys the loaders asked for. After the last loader has run, the program calls
// rejectUnknownKeys() on the root: a key no loader asked for (a misspelling such as
// `speed_scal`) throws, naming the file, the field and the nearest known key. Sections read by
// another program (e.g. the `node:` section of a shared file) are declared with ignore().

#include <Eigen/Core>

#include <cmath>
#include <memory>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

namespace ehc_common {

class ConfigNode {
 public:
  /// Parses `path`. `owner` is the class name used as the error prefix, e.g. "RobotConfig".
  /// A top-level `extends: <file>` (relative to this file) loads that file first and merges
  /// this one over it: mappings merge key by key, anything else (scalars, lists) is replaced.
  /// Chains of up to 8 files. A relative path in a file is resolved against that file's folder
  /// (requirePath, getPath: the base file's `robot: ../robots/x/robot.yaml` stays the base's),
  /// and errors name the file a field's value came from.
  static ConfigNode loadFile(const std::string& path, const std::string& owner);
  /// Parses YAML text (tests, embedded defaults). `origin` stands in for the file name.
  static ConfigNode loadString(const std::string& text, const std::string& origin,
                               const std::string& owner);

  ConfigNode(YAML::Node node, std::string file, std::string field, std::string owner);

  bool has(const std::string& key) const;
  /// Required mapping child; throws if missing or not a mapping.
  ConfigNode child(const std::string& key) const;
  /// Optional child: returns an empty node (every get() then yields its default).
  ConfigNode childOrEmpty(const std::string& key) const;

  /// Optional scalar with default. Numbers must be finite.
  template <class T>
  T get(const std::string& key, const T& fallback) const {
    if (!has(key)) return fallback;
    return require<T>(key);
  }
  /// Required scalar. Numbers must be finite.
  template <class T>
  T require(const std::string& key) const {
    const YAML::Node n = value(key);
    T out;
    try {
      out = n.as<T>();
    } catch (const YAML::Exception&) {
      fail(key, "has the wrong type (value: '" + dump(n) + "')");
    }
    checkFinite(key, out);
    return out;
  }
  /// Optional numeric list; `expected_size` < 0 accepts any length.
  Eigen::VectorXd getVector(const std::string& key, const Eigen::VectorXd& fallback,
                            int expected_size = -1) const;
  Eigen::VectorXd requireVector(const std::string& key, int expected_size = -1) const;
  std::vector<std::string> getStrings(const std::string& key,
                                      const std::vector<std::string>& fallback) const;

  /// Runs `params.validate()`; a std::invalid_argument it throws is rethrown with this node's
  /// file (and the files it extends) and field appended, so cross-field errors also say where
  /// they come from.
  template <class P>
  void validate(const P& params) const {
    try {
      params.validate();
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(std::string(e.what()) + " (in " + fileChain() +
                                  (field_.empty() ? std::string() : ", " + field_) + ")");
    }
  }

  /// Throws std::invalid_argument "[Owner] file: field 'a.b.key' <what>".
  [[noreturn]] void fail(const std::string& key, const std::string& what) const;
  std::string fieldName(const std::string& key) const;
  /// Required file path `key`: absolute as given, relative to the folder of the file the value
  /// came from (through `extends:`, the base file's folder for a value set there). Not empty.
  std::string requirePath(const std::string& key) const;
  /// Optional file path `key` (as requirePath); `fallback` (unchanged) if absent.
  std::string getPath(const std::string& key, const std::string& fallback) const;
  /// The file `key`'s value came from (the loaded file, or a file it extends).
  std::string fileOf(const std::string& key) const;
  /// Optional number `key` in [lo, hi]; an error names the file and the field.
  template <class T>
  T getInRange(const std::string& key, const T& fallback, double lo, double hi) const {
    const T v = get<T>(key, fallback);
    if (!(static_cast<double>(v) >= lo && static_cast<double>(v) <= hi)) {
      std::ostringstream os;
      os << "= " << v << " is outside [" << lo << ", " << hi << "]";
      fail(key, os.str());
    }
    return v;
  }

  const std::string& file() const { return file_; }
  const std::string& owner() const { return owner_; }
  /// The raw YAML of this node. Reading through it is not recorded: use child(), element()
  /// and the getters, or mark what you parse yourself with ignore().
  const YAML::Node& yaml() const { return node_; }
  /// Number of elements of list `key` (0 if absent); fails if it is not a list.
  std::size_t listSize(const std::string& key) const;
  /// Element `i` of list `key`, a mapping, whose field names read "key[i].field".
  ConfigNode element(const std::string& key, std::size_t i) const;
  /// Keys of this mapping node, in file order.
  std::vector<std::string> keys() const;

  /// Declares `key` of this node (and everything below it) as read by another program.
  void ignore(const std::string& key) const;
  /// Every key of this node's document (below this node) that no loader asked for, as field
  /// names ("a.b.key", list elements "a.list[2].key").
  std::vector<std::string> unknownKeys() const;
  /// Throws std::invalid_argument "[Owner] file: unknown field 'a.b.key' (did you mean
  /// 'a.b.other'?)" for the first unknown key; lists the rest in the same message.
  void rejectUnknownKeys() const;

 /// Field name -> the file that set it, for a document merged through `extends:` (a field not
  /// listed came from its nearest listed parent; "" is the first file of the chain).
  using Origins = std::map<std::string, std::string>;

 private:
  YAML::Node value(const std::string& key) const;
  ConfigNode sub(const YAML::Node& n, const std::string& field) const;
  std::string originOf(const std::string& field) const;
  /// "file" or "base.yaml (through 'extends' of file)" for `field`.
  std::string where(const std::string& field) const;
  /// "file" or "file (extends base.yaml, ...)": every file of the document.
  std::string fileChain() const;
  static std::string dump(const YAML::Node& n);
  template <class T>
  void checkFinite(const std::string& key, const T& v) const {
    if constexpr (std::is_floating_point<T>::value) {
      if (!std::isfinite(v)) fail(key, "must be a finite number");
    }
  }

  /// Shared by every node of one document: field names asked for (present or not) and the
  /// subtrees counted as read whole.
  struct Usage {
    std::set<std::string> asked;
    std::set<std::string> whole;
  };
  void mark(const std::string& key) const;
  bool used(const std::string& field) const;
  void collectUnknown(const YAML::Node& n, const std::string& field, std::vector<std::string>* out) const;

  YAML::Node node_;
  std::string file_;
  std::string field_;
  std::string owner_;
  std::shared_ptr<Usage> usage_ = std::make_shared<Usage>();
  std::shared_ptr<const Origins> origins_;  ///< null: one file, every field from file_
};

/// Helpers for validation rules shared by every parameter struct.
void requireRange(const std::string& owner, const std::string& field, double value, double lo,
                  double hi);
void requirePositive(const std::string& owner, const std::string& field, double value);

}  // namespace ehc_common
