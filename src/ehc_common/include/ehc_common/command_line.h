#pragma once
// CommandLine: the one strict "--flag value" parser of the project's command-line tools
// (ehc_reachability, ehc_kinematics, ehc_experiment, ehc_detect_tags, ehc_grasps). Every flag a
// tool accepts is declared up front; an unknown flag, a flag given twice, a missing value or a
// value that does not parse completely (`--samples 1e6`, `--sets 10x`, `--resolution abc`) is an
// error naming the flag. ROS-free. Errors: std::invalid_argument "[CommandLine] --flag: ...".

#include <Eigen/Core>

#include <map>
#include <string>
#include <vector>

namespace ehc_common {

class CommandLine {
 public:
  /// Parses argv[first..argc). `options` take one value, `switches` none ("-h" is read as
  /// "--help" if "help" is a switch). Names are given without the leading "--".
  CommandLine(int argc, const char* const* argv, const std::vector<std::string>& options,
              const std::vector<std::string>& switches, int first = 1);

  bool has(const std::string& name) const;  ///< option given or switch set
  /// Value of an option; throws if it was not given ("--name is required").
  std::string text(const std::string& name) const;
  std::string text(const std::string& name, const std::string& fallback) const;
  /// Whole-string decimal integer in [lo, hi]; `fallback` if the option was not given.
  long integer(const std::string& name, long fallback, long lo, long hi) const;
  /// Whole-string finite real number; `fallback` if the option was not given.
  double real(const std::string& name, double fallback) const;
  /// Comma-separated finite reals ("0.1,0.2,0.3"); `fallback` if the option was not given.
  std::vector<double> reals(const std::string& name, const std::vector<double>& fallback) const;
  /// Exactly three comma-separated finite reals.
  Eigen::Vector3d vector3(const std::string& name, const Eigen::Vector3d& fallback) const;
  /// One of `choices`; `fallback` if the option was not given.
  std::string choice(const std::string& name, const std::vector<std::string>& choices,
                     const std::string& fallback) const;

  /// The parsers the members use, for values that come from elsewhere (e.g. a positional word).
  static long parseInteger(const std::string& flag, const std::string& value, long lo, long hi);
  static double parseReal(const std::string& flag, const std::string& value);
  static std::vector<double> parseReals(const std::string& flag, const std::string& value);

 private:
  void checkDeclared(const std::string& name) const;
  std::vector<std::string> options_, switches_;
  std::map<std::string, std::string> values_;
};

}  // namespace ehc_common
