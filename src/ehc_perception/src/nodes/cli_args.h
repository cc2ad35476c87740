#pragma once
// Minimal "--key value" argument parsing shared by the perception CLIs (no ROS).

#include <Eigen/Core>

#include <cmath>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace ehc_perception::cli {

/// Parses "--key value" pairs; flags listed in `flags` take no value. Throws on a stray word.
inline std::map<std::string, std::string> parseArgs(int argc, char** argv,
                                                    const std::vector<std::string>& flags = {}) {
  std::map<std::string, std::string> out;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a.rfind("--", 0) != 0) throw std::invalid_argument("unexpected argument '" + a + "'");
    const std::string key = a.substr(2);
    bool is_flag = false;
    for (const auto& f : flags) is_flag |= f == key;
    if (is_flag) {
      out[key] = "1";
      continue;
    }
    if (i + 1 >= argc) throw std::invalid_argument("option '" + a + "' needs a value");
    out[key] = argv[++i];
  }
  return out;
}

inline double parseDouble(const std::string& key, const std::string& s) {
  std::size_t pos = 0;
  double v = 0.0;
  try {
    v = std::stod(s, &pos);
  } catch (const std::exception&) {
    pos = 0;
  }
  if (pos != s.size() || !std::isfinite(v))
    throw std::invalid_argument("--" + key + " expects a finite number, got '" + s + "'");
  return v;
}

inline Eigen::Vector3d parseVector3(const std::string& key, const std::string& s) {
  std::vector<double> v;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) v.push_back(parseDouble(key, item));
  if (v.size() != 3) throw std::invalid_argument("--" + key + " expects x,y,z, got '" + s + "'");
  return Eigen::Vector3d(v[0], v[1], v[2]);
}

}  // namespace ehc_perception::cli
