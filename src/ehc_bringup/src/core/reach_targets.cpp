#include "ehc_bringup/reach_targets.h"

#include "ehc_common/enum_names.h"
#include "ehc_control/pose_math.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <random>
#include <sstream>
#include <stdexcept>

namespace ehc_bringup {

namespace {
constexpr ehc_common::EnumNames<TiltSampling, 2> kTiltNames = {{
    {TiltSampling::Uniform, "uniform"},
    {TiltSampling::Sphere, "sphere"},
}};
}  // namespace

std::string toString(TiltSampling s) { return ehc_common::enumName(kTiltNames, s, "ReachTargetGenerator"); }
TiltSampling tiltSamplingFromString(const std::string& s) {
  return ehc_common::enumValue(kTiltNames, s, "ReachTargetGenerator", "tilt sampling");
}

std::vector<std::string> ReachTargetGenerator::presetNames() { return {"paper", "any"}; }

ReachTargetGenerator ReachTargetGenerator::preset(const std::string& name) {
  ReachTargetGenerator g;
  if (name == "paper") return g;
  if (name == "any") {
    g.min_distance = 0.0;
    g.max_distance = 7.0;
    g.max_tilt_deg = 180.0;
    g.tilt_sampling = TiltSampling::Sphere;
    g.tilt_azimuth_spread_deg = 180.0;
    return g;
  }
  throw std::invalid_argument("[ReachTargetGenerator] unknown generator '" + name + "' (paper, any)");
}

std::string ReachTargetGenerator::summary() const {
  std::ostringstream s;
  s << "targets " << min_distance << "-" << max_distance << " m apart, height " << min_height << "-" << max_height
    << " m, tilt " << toString(tilt_sampling) << " up to " << max_tilt_deg << " deg, azimuth within +-"
    << tilt_azimuth_spread_deg << " deg of the travel direction";
  return s.str();
}

void ReachTargetGenerator::validate() const {
  auto bad = [](const std::string& w) { throw std::invalid_argument("[ReachTargetGenerator] " + w); };
  if (!(min_distance >= 0 && max_distance >= min_distance)) bad("need 0 <= min_distance <= max_distance");
  if (!(min_height >= 0 && max_height >= min_height)) bad("need 0 <= min_height <= max_height");
  if (!(max_tilt_deg >= 0 && max_tilt_deg <= 180)) bad("max_tilt_deg must be in [0, 180]");
  if (!(tilt_azimuth_spread_deg >= 0 && tilt_azimuth_spread_deg <= 180))
    bad("tilt_azimuth_spread_deg must be in [0, 180]");
}

std::vector<Eigen::Isometry3d> ReachTargetGenerator::generate(
    int count, unsigned seed, const Eigen::Vector2d& start_xy,
    const std::function<bool(const Eigen::Isometry3d&)>& reachable, int* rejected) const {
  validate();
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> dist(min_distance, max_distance);
  std::uniform_real_distribution<double> angle(-M_PI, M_PI);
  std::uniform_real_distribution<double> height(min_height, max_height);
  const double max_tilt = max_tilt_deg * M_PI / 180.0;
  std::uniform_real_distribution<double> tilt(0.0, max_tilt);
  // Sphere: cos(tilt) uniform in [cos(max), 1] gives directions uniform over the cap.
  std::uniform_real_distribution<double> cos_tilt(std::cos(max_tilt), 1.0);
  const double spread = tilt_azimuth_spread_deg * M_PI / 180.0;
  std::uniform_real_distribution<double> azimuth_offset(-spread, spread);
  std::vector<Eigen::Isometry3d> out;
  Eigen::Vector2d prev = start_xy;
  if (rejected) *rejected = 0;
  int redraws = 0;
  for (int i = 0; i < count; ++i) {
    const double d = dist(rng), bearing = angle(rng), z = height(rng);
    const double t = tilt_sampling == TiltSampling::Sphere ? std::acos(std::clamp(cos_tilt(rng), -1.0, 1.0)) : tilt(rng);
    const double azimuth = bearing + azimuth_offset(rng), roll = angle(rng);
    const Eigen::Vector2d xy = prev + d * Eigen::Vector2d(std::cos(bearing), std::sin(bearing));
    // Straight down = rotation of pi about x (z -> -z); then tilt about the horizontal axis
    // perpendicular to the azimuth, so the approach axis leans towards the azimuth; roll about
    // the approach axis.
    const Eigen::Vector3d tilt_axis(-std::sin(azimuth), std::cos(azimuth), 0.0);
    const Eigen::Matrix3d R = (Eigen::AngleAxisd(-t, tilt_axis) *
                               Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()) *
                               Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitZ()))
                                  .toRotationMatrix();
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = R;
    T.translation() << xy.x(), xy.y(), z;
    if (reachable && !reachable(T)) {
      if (rejected) ++*rejected;
      if (++redraws > 1000)
        throw std::invalid_argument("[ReachTargetGenerator] no reachable target in 1000 draws");
      --i;
      continue;
    }
    redraws = 0;
    out.push_back(T);
    prev = xy;
  }
  return out;
}

std::vector<Eigen::Isometry3d> readReachTargetsCsv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::invalid_argument("[ReachTargets] cannot read targets file '" + path + "'");
  std::vector<Eigen::Isometry3d> out;
  std::string line;
  int lineno = 0;
  while (std::getline(in, line)) {
    ++lineno;
    const auto hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    for (char& c : line)
      if (c == ',' || c == '\t') c = ' ';
    std::istringstream ss(line);
    std::vector<double> v;
    std::string tok;
    while (ss >> tok) {
      try {
        std::size_t used = 0;
        v.push_back(std::stod(tok, &used));
        if (used != tok.size()) throw std::invalid_argument(tok);
      } catch (const std::exception&) {
        // A header row (x y z qx ...) is allowed as the first non-empty line.
        if (out.empty() && v.empty() && tok == "x") { v.clear(); break; }
        throw std::invalid_argument("[ReachTargets] " + path + ":" + std::to_string(lineno) +
                                    ": '" + tok + "' is not a number");
      }
    }
    if (v.empty()) continue;
    const auto where = "[ReachTargets] " + path + ":" + std::to_string(lineno) + ": ";
    if (v.size() != 7) throw std::invalid_argument(where + "expected 7 values x y z qx qy qz qw");
    for (double x : v)
      if (!std::isfinite(x)) throw std::invalid_argument(where + "values must be finite");
    const Eigen::Quaterniond q(v[6], v[3], v[4], v[5]);
    if (!ehc_control::isRotationQuaternion(q))
      throw std::invalid_argument(where + "quaternion is not unit length");
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = q.normalized().toRotationMatrix();
    T.translation() << v[0], v[1], v[2];
    out.push_back(T);
  }
  if (out.empty()) throw std::invalid_argument("[ReachTargets] " + path + ": no targets");
  return out;
}

void writeReachTargetsCsv(const std::string& path, const std::vector<Eigen::Isometry3d>& targets) {
  std::ofstream out(path);
  if (!out) throw std::invalid_argument("[ReachTargets] cannot write '" + path + "'");
  out << "# x y z qx qy qz qw (odom frame, TCP pose, z = approach axis)\n" << std::setprecision(10);
  for (const auto& T : targets) {
    const Eigen::Quaterniond q(T.linear());
    out << T.translation().x() << " " << T.translation().y() << " " << T.translation().z() << " "
        << q.x() << " " << q.y() << " " << q.z() << " " << q.w() << "\n";
  }
}

std::vector<Eigen::Isometry3d> relativeToPrevious(const std::vector<Eigen::Isometry3d>& targets,
                                                  const Eigen::Vector2d& start_xy) {
  std::vector<Eigen::Isometry3d> out;
  out.reserve(targets.size());
  Eigen::Vector2d previous = start_xy;
  for (const Eigen::Isometry3d& t : targets) {
    Eigen::Isometry3d r = t;
    r.translation().head<2>() += start_xy - previous;
    previous = t.translation().head<2>();
    out.push_back(r);
  }
  return out;
}

}  // namespace ehc_bringup
