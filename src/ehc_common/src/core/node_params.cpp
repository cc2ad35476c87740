#include "ehc_common/node_params.h"

#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace ehc_common {

ParamValue ParamValue::ofBool(bool v) {
  ParamValue p;
  p.kind = Kind::Bool;
  p.b = v;
  return p;
}
ParamValue ParamValue::ofInt(long v) {
  ParamValue p;
  p.kind = Kind::Int;
  p.i = v;
  return p;
}
ParamValue ParamValue::ofDouble(double v) {
  ParamValue p;
  p.kind = Kind::Double;
  p.d = v;
  return p;
}
ParamValue ParamValue::ofString(std::string v) {
  ParamValue p;
  p.kind = Kind::String;
  p.s = std::move(v);
  return p;
}

std::string ParamValue::text() const {
  std::ostringstream os;
  switch (kind) {
    case Kind::Bool: os << (b ? "true" : "false"); break;
    case Kind::Int: os << i; break;
    case Kind::Double: os << d; break;
    case Kind::String: os << s; break;
    case Kind::List:
      os << "[";
      for (std::size_t k = 0; k < items.size(); ++k) os << (k ? ", " : "") << items[k].text();
      os << "]";
      break;
    case Kind::Map: os << "{...}"; break;
  }
  return os.str();
}

NodeParams::NodeParams(std::string node, std::map<std::string, ParamValue> values, std::set<std::string> command_line)
    : node_(std::move(node)), values_(std::move(values)), command_line_(std::move(command_line)) {}

const ParamValue* NodeParams::lookup(const std::string& name) const {
  asked_.insert(name);
  const auto it = values_.find(name);
  return it == values_.end() ? nullptr : &it->second;
}

bool NodeParams::has(const std::string& name) const { return lookup(name) != nullptr; }

void NodeParams::fail(const std::string& name, const std::string& what) const {
  throw std::invalid_argument("[NodeParams] private parameter '_" + name + "' " + what);
}

void NodeParams::checkRange(const std::string& name, double v, double lo, double hi) const {
  if (std::isfinite(v) && v >= lo && v <= hi) return;
  std::ostringstream os;
  os << "= " << v << " is outside [" << lo << ", " << hi << "]";
  fail(name, os.str());
}

namespace {
const char* kindName(ParamValue::Kind k) {
  switch (k) {
    case ParamValue::Kind::Bool: return "a bool";
    case ParamValue::Kind::Int: return "an integer";
    case ParamValue::Kind::Double: return "a real number";
    case ParamValue::Kind::String: return "text";
    case ParamValue::Kind::List: return "a list";
    case ParamValue::Kind::Map: return "a dictionary";
  }
  return "?";
}
}  // namespace

template <>
std::optional<bool> NodeParams::getOptional<bool>(const std::string& name) const {
  const ParamValue* v = lookup(name);
  if (!v) return std::nullopt;
  if (v->kind != ParamValue::Kind::Bool) fail(name, "must be true or false (got " + std::string(kindName(v->kind)) + " '" + v->text() + "')");
  return v->b;
}

template <>
std::optional<long> NodeParams::getOptional<long>(const std::string& name) const {
  const ParamValue* v = lookup(name);
  if (!v) return std::nullopt;
  if (v->kind != ParamValue::Kind::Int) fail(name, "must be an integer (got " + std::string(kindName(v->kind)) + " '" + v->text() + "')");
  return v->i;
}

template <>
std::optional<int> NodeParams::getOptional<int>(const std::string& name) const {
  const std::optional<long> v = getOptional<long>(name);
  if (!v) return std::nullopt;
  checkRange(name, static_cast<double>(*v), std::numeric_limits<int>::min(), std::numeric_limits<int>::max());
  return static_cast<int>(*v);
}

template <>
std::optional<unsigned> NodeParams::getOptional<unsigned>(const std::string& name) const {
  const std::optional<long> v = getOptional<long>(name);
  if (!v) return std::nullopt;
  checkRange(name, static_cast<double>(*v), 0.0, std::numeric_limits<unsigned>::max());
  return static_cast<unsigned>(*v);
}

template <>
std::optional<double> NodeParams::getOptional<double>(const std::string& name) const {
  const ParamValue* v = lookup(name);
  if (!v) return std::nullopt;
  if (v->kind == ParamValue::Kind::Int) return static_cast<double>(v->i);
  if (v->kind != ParamValue::Kind::Double || !std::isfinite(v->d))
    fail(name, "must be a finite number (got " + std::string(kindName(v->kind)) + " '" + v->text() + "')");
  return v->d;
}

template <>
std::optional<std::string> NodeParams::getOptional<std::string>(const std::string& name) const {
  const ParamValue* v = lookup(name);
  if (!v) return std::nullopt;
  if (v->kind != ParamValue::Kind::String) fail(name, "must be text (got " + std::string(kindName(v->kind)) + " '" + v->text() + "')");
  return v->s;
}

std::string NodeParams::requireText(const std::string& name, const std::string& what) const {
  const std::optional<std::string> v = getOptional<std::string>(name);
  if (!v || v->empty())
    throw std::invalid_argument("[NodeParams] missing private parameter _" + name + ":=" + what);
  return *v;
}

std::vector<std::string> NodeParams::getList(const std::string& name) const {
  const ParamValue* v = lookup(name);
  std::vector<std::string> out;
  if (!v) return out;
  if (v->kind == ParamValue::Kind::List) {
    for (const ParamValue& item : v->items) {
      if (item.kind != ParamValue::Kind::String) fail(name, "must be a list of names (item '" + item.text() + "')");
      out.push_back(item.s);
    }
    return out;
  }
  if (v->kind != ParamValue::Kind::String) fail(name, "must be a list of names (got '" + v->text() + "')");
  return splitNameList(v->s);
}

std::vector<std::string> splitNameList(const std::string& text) {
  std::vector<std::string> out;
  std::string item;
  for (const char ch : text + ",") {
    if (ch == ',' || ch == ' ' || ch == '[' || ch == ']') {
      if (!item.empty()) out.push_back(item);
      item.clear();
    } else {
      item += ch;
    }
  }
  return out;
}

std::vector<std::string> NodeParams::unread() const {
  std::vector<std::string> out;
  for (const auto& kv : values_)
    if (!asked_.count(kv.first)) out.push_back(kv.first);
  return out;
}

void NodeParams::rejectUnknown() const {
  std::string unknown;
  for (const std::string& name : unread())
    if (command_line_.count(name)) unknown += (unknown.empty() ? "'_" : ", '_") + name + "'";
  if (unknown.empty()) return;
  std::string known;
  for (const std::string& a : asked_) known += (known.empty() ? "_" : ", _") + a;
  throw std::invalid_argument("[NodeParams] unknown private parameter " + unknown + " of " + node_ + " (it reads " +
                              (known.empty() ? std::string("none") : known) + ")");
}

std::string NodeParams::overrides() const {
  std::string s;
  for (const auto& kv : values_)
    if (asked_.count(kv.first)) s += (s.empty() ? "_" : ", _") + kv.first + ":=" + kv.second.text();
  return s;
}

std::string NodeParams::summary() const {
  std::string s;
  for (const auto& kv : values_) {
    if (!asked_.count(kv.first)) continue;
    s += (s.empty() ? "_" : ", _") + kv.first + ":=" + kv.second.text() +
         (command_line_.count(kv.first) ? " (command line)" : " (parameter server)");
  }
  return s.empty() ? "none" : s;
}

std::set<std::string> commandLineParamNames(int argc, const char* const* argv) {
  std::set<std::string> names;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const auto pos = a.find(":=");
    if (pos == std::string::npos || pos < 2 || a[0] != '_' || a[1] == '_') continue;
    names.insert(a.substr(1, pos - 1));
  }
  return names;
}

}  // namespace ehc_common
