#pragma once
// Targets for Exp-1 (random reaching): a seeded generator and a CSV reader/writer.
// A target is a TCP pose in the world (odom) frame; its z axis is the approach direction.

#include <Eigen/Geometry>

#include <functional>
#include <string>
#include <vector>

namespace ehc_bringup {

/// How the tilt of the approach axis from straight down is drawn.
enum class TiltSampling {
  Uniform,  ///< tilt angle U[0, max_tilt] (the paper-style generator)
  Sphere,   ///< approach direction uniform on the spherical cap of half-angle max_tilt
};
std::string toString(TiltSampling s);
TiltSampling tiltSamplingFromString(const std::string& s);  ///< throws "[ReachTargetGenerator] ..."

struct ReachTargetGenerator {
  double min_distance = 1.5;  ///< m, horizontal distance from the previous target (or start)
  double max_distance = 4.0;
  double min_height = 0.3;    ///< m above the floor
  double max_height = 1.0;
  double max_tilt_deg = 90.0;  ///< approach axis tilted at most this far from straight down
  TiltSampling tilt_sampling = TiltSampling::Uniform;
  /// The tilt leans along the travel direction (bearing from the previous target) rotated by
  /// U[-spread, spread]: 45 deg, targets are approached from the side the robot arrives from;
  /// 180 deg, from any side.
  double tilt_azimuth_spread_deg = 45.0;
  void validate() const;       ///< throws "[ReachTargetGenerator] ..."
  std::string summary() const;  ///< one line, every field

  /// Named distributions: "paper" (the defaults above: 1.5-4 m apart, tilt U[0, 90] deg leaning
  /// within +-45 deg of the travel direction) and "any" (0-7 m apart, approach direction
  /// uniform over the sphere, from any side, from above to below the horizontal).
  static ReachTargetGenerator preset(const std::string& name);  ///< throws "[ReachTargetGenerator] ..."
  static std::vector<std::string> presetNames();

  /// `count` targets; each is U[min, max] m horizontally from the previous one (the first
  /// from `start_xy`) at a uniform bearing, so the sequence does not depend on the controller.
  /// With `reachable` set, a drawn target that fails it is drawn again (at most 1000 times;
  /// then "[ReachTargetGenerator] ..." is thrown); `rejected` counts the redrawn targets.
  std::vector<Eigen::Isometry3d> generate(int count, unsigned seed,
                                          const Eigen::Vector2d& start_xy = Eigen::Vector2d::Zero(),
                                          const std::function<bool(const Eigen::Isometry3d&)>& reachable = nullptr,
                                          int* rejected = nullptr) const;
};

/// The targets of a back-to-back sequence (each drawn relative to the previous one, the first
/// relative to `start_xy`) shifted horizontally so that each is relative to `start_xy`: the
/// same approaches, each from the start (ReachProtocol::Reset). Orientation and height kept.
std::vector<Eigen::Isometry3d> relativeToPrevious(const std::vector<Eigen::Isometry3d>& targets,
                                                  const Eigen::Vector2d& start_xy = Eigen::Vector2d::Zero());

/// Reads rows `x y z qx qy qz qw` (space or comma separated; '#' starts a comment).
/// Throws "[ReachTargets] <file>:<line>: ..." on malformed rows or non-unit quaternions.
std::vector<Eigen::Isometry3d> readReachTargetsCsv(const std::string& path);
void writeReachTargetsCsv(const std::string& path, const std::vector<Eigen::Isometry3d>& targets);

}  // namespace ehc_bringup
