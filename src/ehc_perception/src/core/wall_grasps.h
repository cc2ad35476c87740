#pragma once
// Wall grasps: one finger on a surface the view shows, the other beyond the object's far side
// where the view proves there is nothing, closing across the wall between them (a bowl's or a
// cup's rim, a thin plate, any part whose far side a single view does not show). Internal to
// ehc_perception_core.
//
// The far side is not assumed: it is bounded by the view. Every surface of the object that the
// camera does not see lies behind a surface it does see, along the camera's rays (ViewShadow).
// The finger on the unseen side is placed at the nearest position along the closing axis where
// none of its volume (and none of its path in from above) may lie behind a seen point: the
// object then lies between the seen contact and that finger, whatever its hidden shape, so the
// width (seen contact to that finger) never under-measures the object. At a bowl's far rim the
// camera sees the inner wall from above and, just past the rim, the table: the shadow behind the
// rim widens with the depth below it (depth / tan(elevation)), so a finger reaching 15 mm below
// the rim closes across the wall plus 10-30 mm of shadow, well inside the opening.
//
// The centre: the fingers close symmetrically about it, so a centre nearer one face than the
// other pushes the object with one finger before the other touches (a rim grasp centred midway
// between the seen contact and the bound sits 5-15 mm off the wall: the bowl slides away from
// the closing fingers). Where the view shows the wall's top between the fingers (a rim seen from
// above; within the noise band above them), the wall's far face is where that top ends: the grasp
// is centred on the middle of the seen thickness, from the seen contact to the object's farthest
// point between the fingers short of the bound, or as near it as the opening allows with the far
// finger at its bound (fully open, the fingers reach at most half the opening from the centre).
// Elsewhere (a face whose top the view does not show there) it stays midway to the bound.
//
// Hypotheses: every seen point whose normal (turned towards the camera: the side the view shows)
// is within the friction cone of the horizontal, closing horizontally into the surface,
// approached straight down and, with wall_tilt_deg, tilted by that about the closing axis (the
// approach's horizontal part along the wall, away from the camera: the hand comes from the
// robot's side, its wrist nearer the robot), the grasp's closing line at the point's height.
// Every check below is made in the grasp's frame, tilted or not ("above": back along the
// approach). The seen contact is the median of the seen points around it facing the finger
// (within the friction cone); the unseen side's normal is not known (a wall's two faces are
// about parallel): such grasps rank as grasps with one seen contact
// (GraspGeneratorConfig::wall_weight x the seen normal's cosine).
// Checked: no seen surface in the seen-side finger beyond its inner face (facing the finger:
// by more than the noise; a tilted finger's far corner on a curved rim); fingers (and the outer
// one's path from approach_standoff above) and the palm against
// the cloud and the other objects' points, the fingers against the support, the seen-side finger
// and the palm against the hidden volume.

#include "ehc_perception/grasp_generator.h"

#include <Eigen/Core>

#include <vector>

namespace ehc_perception {
namespace detail {

/// What a single view may hide: the space behind its points along the camera's rays. A point q
/// may be solid if some seen point's ray passes within `tolerance` (rad; about the cloud's angular
/// pitch, so gaps between samples inside the silhouette count as seen surface) of q's ray and q is
/// behind it or less than `margin` in front (depth noise). Conservative: behind a point seen from
/// another side everything counts as possibly solid too.
class ViewShadow {
 public:
  ViewShadow() = default;
  ViewShadow(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& eye, double tolerance, double margin);
  bool enabled() const { return enabled_; }
  bool mayBeSolid(const Eigen::Vector3d& q) const;

 private:
  bool project(const Eigen::Vector3d& q, double* u, double* v, double* r) const;
  bool enabled_ = false;
  Eigen::Vector3d eye_ = Eigen::Vector3d::Zero(), fwd_ = Eigen::Vector3d::UnitZ(), e1_ = Eigen::Vector3d::UnitX(),
                  e2_ = Eigen::Vector3d::UnitY();
  double tol_ = 0.0, margin_ = 0.0, cell_ = 1.0, u0_ = 0.0, v0_ = 0.0;
  int nu_ = 0, nv_ = 0;
  std::vector<int> start_;             ///< per cell, its first entry in pts_ (cells + 1 entries)
  std::vector<Eigen::Vector3f> pts_;   ///< (u, v, range) sorted by cell
};

/// The inputs of wallGrasps: the object's points with their normals (any sign; zero where none),
/// the view's shadow and the support (n.p + d = 0, n up), the cloud's noise and voxel edge.
struct WallInput {
  const std::vector<Eigen::Vector3d>* points = nullptr;
  const std::vector<Eigen::Vector3d>* normals = nullptr;
  const ViewShadow* shadow = nullptr;
  Eigen::Vector3d eye = Eigen::Vector3d::Zero();
  Eigen::Vector4d plane = Eigen::Vector4d::Zero();
  double noise = 0.0, leaf = 0.004;
};

struct WallGrasp {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();  ///< grasp frame (y closing, z approach)
  Eigen::Vector3d c = Eigen::Vector3d::Zero();      ///< grasp centre
  double width = 0.0;           ///< opening: measured width + 2 x clearance
  double measured_width = 0.0;  ///< seen contact to the nearest position the view proves free
  double contact_y = 0.0;       ///< the seen contact along the closing axis from c (< 0)
  double cos_n = 0.0;           ///< the seen contact's normal against the closing axis
};

/// Wall grasps on the object (see the file comment), at most a quarter of cfg.max_seeds
/// hypotheses tried (evenly among the seen points facing horizontally). `collision`: every point
/// the gripper must not hit (the object's included).
std::vector<WallGrasp> wallGrasps(const GraspGeneratorConfig& cfg, const WallInput& in,
                                  const std::vector<Eigen::Vector3d>& collision);

}  // namespace detail
}  // namespace ehc_perception
