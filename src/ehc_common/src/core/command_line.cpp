#include "ehc_common/command_line.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <stdexcept>

namespace ehc_common {

namespace {
[[noreturn]] void fail(const std::string& flag, const std::string& what) {
  throw std::invalid_argument("[CommandLine] " + (flag.empty() ? std::string() : flag + ": ") +
                              what);
}
bool contains(const std::vector<std::string>& v, const std::string& s) {
  return std::find(v.begin(), v.end(), s) != v.end();
}
bool blank(const std::string& s) {
  return s.empty() || s.find_first_not_of(" \t\n") == std::string::npos;
}
}  // namespace

CommandLine::CommandLine(int argc, const char* const* argv,
                         const std::vector<std::string>& options,
                         const std::vector<std::string>& switches, int first)
    : options_(options), switches_(switches) {
  for (int i = first; i < argc; ++i) {
    std::string word = argv[i];
    if (word == "-h" && contains(switches_, "help")) word = "--help";
    if (word.rfind("--", 0) != 0 || word.size() < 3)
      fail("", "unexpected argument '" + word + "' (flags start with --)");
    const std::string name = word.substr(2);
    if (values_.count(name)) fail(word, "given twice");
    if (contains(switches_, name)) {
      values_[name] = "";
    } else if (contains(options_, name)) {
      if (i + 1 >= argc) fail(word, "needs a value");
      values_[name] = argv[++i];
    } else {
      std::string known;
      for (const auto& o : options_) known += " --" + o;
      for (const auto& s : switches_) known += " --" + s;
      fail(word, "unknown flag (known:" + known + ")");
    }
  }
}

void CommandLine::checkDeclared(const std::string& name) const {
  if (!contains(options_, name) && !contains(switches_, name))
    throw std::logic_error("[CommandLine] flag --" + name + " was not declared");
}

bool CommandLine::has(const std::string& name) const {
  checkDeclared(name);
  return values_.count(name) > 0;
}

std::string CommandLine::text(const std::string& name) const {
  checkDeclared(name);
  const auto it = values_.find(name);
  if (it == values_.end()) fail("--" + name, "is required");
  return it->second;
}

std::string CommandLine::text(const std::string& name, const std::string& fallback) const {
  return has(name) ? values_.at(name) : fallback;
}

long CommandLine::integer(const std::string& name, long fallback, long lo, long hi) const {
  return has(name) ? parseInteger("--" + name, values_.at(name), lo, hi) : fallback;
}

double CommandLine::real(const std::string& name, double fallback) const {
  return has(name) ? parseReal("--" + name, values_.at(name)) : fallback;
}

std::vector<double> CommandLine::reals(const std::string& name,
                                       const std::vector<double>& fallback) const {
  return has(name) ? parseReals("--" + name, values_.at(name)) : fallback;
}

Eigen::Vector3d CommandLine::vector3(const std::string& name,
                                     const Eigen::Vector3d& fallback) const {
  if (!has(name)) return fallback;
  const std::vector<double> v = parseReals("--" + name, values_.at(name));
  if (v.size() != 3)
    fail("--" + name, "expects x,y,z (3 numbers), got " + std::to_string(v.size()));
  return Eigen::Vector3d(v[0], v[1], v[2]);
}

std::string CommandLine::choice(const std::string& name, const std::vector<std::string>& choices,
                                const std::string& fallback) const {
  if (!has(name)) return fallback;
  const std::string& v = values_.at(name);
  if (contains(choices, v)) return v;
  std::string list;
  for (const auto& c : choices) list += (list.empty() ? "" : " | ") + c;
  fail("--" + name, "'" + v + "' is not one of " + list);
}

long CommandLine::parseInteger(const std::string& flag, const std::string& value, long lo,
                               long hi) {
  if (blank(value) || std::isspace(static_cast<unsigned char>(value.front())))
    fail(flag, "'" + value + "' is not an integer");
  errno = 0;
  char* end = nullptr;
  const long v = std::strtol(value.c_str(), &end, 10);
  if (end != value.c_str() + value.size())
    fail(flag, "'" + value + "' is not an integer (digits only, e.g. 1000000 not 1e6)");
  if (errno == ERANGE || v < lo || v > hi)
    fail(flag, "'" + value + "' is out of range [" + std::to_string(lo) + ", " +
                   std::to_string(hi) + "]");
  return v;
}

double CommandLine::parseReal(const std::string& flag, const std::string& value) {
  if (blank(value) || std::isspace(static_cast<unsigned char>(value.front())))
    fail(flag, "'" + value + "' is not a number");
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(value.c_str(), &end);
  if (end != value.c_str() + value.size()) fail(flag, "'" + value + "' is not a number");
  if (errno == ERANGE || !std::isfinite(v)) fail(flag, "'" + value + "' is not a finite number");
  return v;
}

std::vector<double> CommandLine::parseReals(const std::string& flag, const std::string& value) {
  std::vector<double> out;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = value.find(',', start);
    out.push_back(parseReal(flag, value.substr(start, comma - start)));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return out;
}

}  // namespace ehc_common
