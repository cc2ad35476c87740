#pragma once
// NodeParams: the one reader of a node's private ROS parameters (`_name:=value` on the rosrun
// command line, or set by a launch file / rosparam in the node's namespace). ROS-free: the node
// side (ehc_common/node_init.h) fetches the namespace once into ParamValues.
//
// Every read is typed and strict, so a wrong value is a start-up error naming the parameter
// instead of a silent fallback: `_mpbs:=maybe` for a bool, `_seed:=abc` or `_seed:=1.5` for an
// integer, `_port:=http` for a port, `_target_timeout:=abc` for a number. Integers are accepted
// where a real number is asked for. After the node has read what it needs, rejectUnknown()
// makes a parameter given on the command line that no reader asked for (`_mdoe:=tsmm`) an error;
// one only on the parameter server is reported by unread() (the node logs it).
// Errors: std::invalid_argument "[NodeParams] private parameter '_name' ...".

#include <map>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace ehc_common {

/// One parameter as the parameter server holds it (XML-RPC types).
struct ParamValue {
  enum class Kind { Bool, Int, Double, String, List, Map };
  Kind kind = Kind::String;
  bool b = false;
  long i = 0;
  double d = 0.0;
  std::string s;                  ///< String
  std::vector<ParamValue> items;  ///< List
  std::string text() const;       ///< the value as a user would write it, for messages
  static ParamValue ofBool(bool v);
  static ParamValue ofInt(long v);
  static ParamValue ofDouble(double v);
  static ParamValue ofString(std::string v);
};

class NodeParams {
 public:
  NodeParams() = default;
  /// `node`: the node's name for the messages; `values`: its private parameters by name
  /// (without "~" or "_"); `command_line`: the names given as `_name:=value` to this run.
  NodeParams(std::string node, std::map<std::string, ParamValue> values, std::set<std::string> command_line);

  bool has(const std::string& name) const;  ///< recorded as asked for
  /// Typed optional parameter: `fallback` when absent. T: bool, int, long, unsigned, double,
  /// std::string. Throws on a value of another type (see the file comment).
  template <class T>
  T get(const std::string& name, const T& fallback) const {
    const std::optional<T> v = getOptional<T>(name);
    return v ? *v : fallback;
  }
  template <class T>
  std::optional<T> getOptional(const std::string& name) const;
  /// A number in [lo, hi] (integers or reals as T); `fallback` when absent (not checked).
  template <class T>
  T getInRange(const std::string& name, const T& fallback, double lo, double hi) const {
    const std::optional<T> v = getOptional<T>(name);
    if (!v) return fallback;
    checkRange(name, static_cast<double>(*v), lo, hi);
    return *v;
  }
  /// A required text parameter: throws "[NodeParams] missing private parameter _name:=<what>".
  std::string requireText(const std::string& name, const std::string& what) const;
  /// Text parameter `name` turned into a T by `parse` (e.g. a mode name); an
  /// std::invalid_argument `parse` throws is rethrown naming the parameter. nullopt when absent.
  template <class T, class F>
  std::optional<T> getParsed(const std::string& name, F&& parse) const {
    const std::optional<std::string> text = getOptional<std::string>(name);
    if (!text) return std::nullopt;
    try {
      return parse(*text);
    } catch (const std::invalid_argument& e) {
      fail(name, "= '" + *text + "': " + e.what());
    }
  }
  /// A list of strings, or one string of items separated by commas, blanks or brackets (rosrun
  /// keeps `_x:=[a,b]` a string): {"a", "b"}. `{}` when absent.
  std::vector<std::string> getList(const std::string& name) const;

  /// Runs `check` (a validate() of parameters the private ones override); a
  /// std::invalid_argument it throws is rethrown with the overrides named, e.g. "... (with the
  /// private parameters _target_timeout:=-1)".
  template <class F>
  void validate(F&& check) const;

  /// Throws for a parameter given on this run's command line that no reader asked for,
  /// naming it and the parameters the node reads.
  void rejectUnknown() const;
  /// Parameters present (only on the parameter server) that no reader asked for.
  std::vector<std::string> unread() const;
  /// "_a:=1 (command line), _b:=x (parameter server)" for every parameter present that was read;
  /// "none" when there is none.
  std::string summary() const;
  const std::string& node() const { return node_; }
  bool fromCommandLine(const std::string& name) const { return command_line_.count(name) > 0; }

 private:
  [[noreturn]] void fail(const std::string& name, const std::string& what) const;
  void checkRange(const std::string& name, double v, double lo, double hi) const;
  const ParamValue* lookup(const std::string& name) const;  ///< records the name as asked for
  std::string overrides() const;

  std::string node_ = "node";
  std::map<std::string, ParamValue> values_;
  std::set<std::string> command_line_;
  mutable std::set<std::string> asked_;
};

/// Items of one string separated by commas, blanks or brackets: "[a, b:c]" -> {"a", "b:c"};
/// "" and "[]" give none.
std::vector<std::string> splitNameList(const std::string& text);

/// The names of the private parameters given on a command line (`_name:=value`; `__name:=` is
/// a ROS special argument, not a parameter), in argv order.
std::set<std::string> commandLineParamNames(int argc, const char* const* argv);

template <> std::optional<bool> NodeParams::getOptional<bool>(const std::string& name) const;
template <> std::optional<int> NodeParams::getOptional<int>(const std::string& name) const;
template <> std::optional<long> NodeParams::getOptional<long>(const std::string& name) const;
template <> std::optional<unsigned> NodeParams::getOptional<unsigned>(const std::string& name) const;
template <> std::optional<double> NodeParams::getOptional<double>(const std::string& name) const;
template <> std::optional<std::string> NodeParams::getOptional<std::string>(const std::string& name) const;

template <class F>
void NodeParams::validate(F&& check) const {
  try {
    check();
  } catch (const std::invalid_argument& e) {
    const std::string o = overrides();
    if (o.empty()) throw;
    throw std::invalid_argument(std::string(e.what()) + " (with the private parameters " + o + ")");
  }
}

}  // namespace ehc_common
