#include "ehc_control/robot_check.h"

#include "ehc_common/config_node.h"
#include "ehc_common/text_format.h"
#include "ehc_control/pinhole_camera.h"
#include "ehc_control/qp_controller.h"
#include "ehc_control/reachability_map.h"
#include "ehc_control/robot_collision_model.h"
#include "ehc_control/robot_config.h"
#include "ehc_control/whole_body_model.h"

#include <urdf_parser/urdf_parser.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <memory>
#include <sstream>
#include <stdexcept>

namespace ehc_control {

namespace {
const char* kOwner = "RobotCheck";

/// The lines of one run; each check adds its problems, or one ok line when it has none.
class Report {
 public:
  void problem(const std::string& check, const std::string& message) { lines_.push_back({check, false, message}); }
  void ok(const std::string& check, const std::string& message) { lines_.push_back({check, true, message}); }
  bool problemsSince(std::size_t mark) const {
    return std::any_of(lines_.begin() + static_cast<long>(mark), lines_.end(), [](const RobotCheckLine& l) { return !l.ok; });
  }
  std::size_t size() const { return lines_.size(); }
  std::vector<RobotCheckLine> take() { return std::move(lines_); }

 private:
  std::vector<RobotCheckLine> lines_;
};

std::string num(double v, int digits = 3) { return ehc_common::fixedDecimals(v, digits); }

std::string vec(const Eigen::Vector3d& v, int digits = 2) {
  return "[" + num(v.x(), digits) + ", " + num(v.y(), digits) + ", " + num(v.z(), digits) + "]";
}

/// The ehc_reachability command that (re)builds the robot's map: with the map's own sample
/// count, seed and direction bins when it has a map.
std::string rebuildCommand(const RobotConfig& rc, const ReachabilityMap* map = nullptr) {
  return "rosrun ehc_control ehc_reachability --robot " + rc.source_file + " --samples " +
         std::to_string(map ? map->samples() : 20000000L) + " --seed " + std::to_string(map ? map->seed() : 1u) +
         " --direction-bins " + std::to_string(map ? map->directionBins() : 6) + " --out " +
         (rc.reachability_map_path.empty() ? std::string("<robot folder>/reachability_map.bin") : rc.reachability_map_path);
}

/// True when `link` is `ancestor` or hangs below it in the URDF tree.
bool hangsBelow(const urdf::ModelInterface& urdf, const std::string& link, const std::string& ancestor) {
  urdf::LinkConstSharedPtr l = urdf.getLink(link);
  while (l) {
    if (l->name == ancestor) return true;
    l = l->getParent();
  }
  return false;
}

bool movable(const urdf::Joint& j) {
  return j.type == urdf::Joint::REVOLUTE || j.type == urdf::Joint::CONTINUOUS || j.type == urdf::Joint::PRISMATIC;
}

void checkFrames(const RobotConfig& rc, const urdf::ModelInterface& urdf, Report& r) {
  const std::size_t mark = r.size();
  const std::string root = urdf.getRoot() ? urdf.getRoot()->name : "";
  const std::pair<const char*, const std::string*> frames[] = {{"base", &rc.base_frame},
                                                                {"arm_base", &rc.arm_base_frame},
                                                                {"tcp", &rc.tcp_frame},
                                                                {"camera_optical", &rc.camera_frame}};
  for (const auto& [field, link] : frames)
    if (!urdf.getLink(*link))
      r.problem("frames", std::string("robot.frames.") + field + " names link '" + *link + "', which is not in the URDF " +
                              rc.urdf_path);
  if (urdf.getLink(rc.base_frame) && root != rc.base_frame)
    r.problem("frames", "robot.frames.base is '" + rc.base_frame + "' but the URDF's root link is '" + root +
                            "' (the root must be the base footprint centre on the floor)");
  for (const FrameOverride& c : rc.calibration) {
    const urdf::JointConstSharedPtr j = urdf.getJoint(c.joint);
    if (!j)
      r.problem("frames", "robot.calibration names joint '" + c.joint + "', which is not in the URDF " + rc.urdf_path);
    else if (j->type != urdf::Joint::FIXED)
      r.problem("frames", "robot.calibration joint '" + c.joint + "' must be a fixed joint (the TCP or camera mount)");
  }
  if (!r.problemsSince(mark))
    r.ok("frames", "base " + rc.base_frame + " (URDF root), arm base " + rc.arm_base_frame + ", TCP " + rc.tcp_frame +
                       ", camera " + rc.camera_frame + ", " + std::to_string(rc.calibration.size()) + " calibrated joint(s)");
}

void checkArmChain(const RobotConfig& rc, const urdf::ModelInterface& urdf, Report& r) {
  const std::size_t mark = r.size();
  for (const std::string& name : rc.arm_joints) {
    const urdf::JointConstSharedPtr j = urdf.getJoint(name);
    if (!j)
      r.problem("arm joints", "robot.arm.joints names joint '" + name + "', which is not in the URDF " + rc.urdf_path);
    else if (!movable(*j))
      r.problem("arm joints", "arm joint '" + name + "' must be revolute, continuous or prismatic in the URDF");
  }
  if (r.problemsSince(mark) || !urdf.getLink(rc.tcp_frame) || !urdf.getLink(rc.arm_base_frame)) return;
  // The movable joints from the arm base down to the TCP, in order.
  std::vector<std::string> chain;
  bool from_arm_base = false;
  for (urdf::LinkConstSharedPtr l = urdf.getLink(rc.tcp_frame); l; l = l->getParent()) {
    if (l->name == rc.arm_base_frame) {
      from_arm_base = true;
      break;
    }
    if (l->parent_joint && movable(*l->parent_joint)) chain.insert(chain.begin(), l->parent_joint->name);
  }
  if (chain != rc.arm_joints || !from_arm_base) {
    std::string found;
    for (const std::string& j : chain) found += (found.empty() ? "" : ", ") + j;
    r.problem("arm joints", "robot.arm.joints must be the movable joints from '" + rc.arm_base_frame + "' to '" +
                                rc.tcp_frame + "' in order; the URDF's chain to the TCP has: " +
                                (found.empty() ? std::string("none") : found) +
                                (from_arm_base ? "" : " (and does not start at the arm base)"));
    return;
  }
  r.ok("arm joints", std::to_string(rc.nArm()) + " joints " + rc.arm_joints.front() + " .. " + rc.arm_joints.back() +
                         " form the chain " + rc.arm_base_frame + " -> " + rc.tcp_frame);
}

void checkJointLimits(const RobotConfig& rc, const urdf::ModelInterface& urdf, const RobotCheckParams& p, Report& r) {
  const std::size_t mark = r.size();
  double least_margin = 1e9;
  for (int i = 0; i < rc.nArm(); ++i) {
    const std::string& name = rc.arm_joints[static_cast<std::size_t>(i)];
    const double lo = rc.arm_lower[i], hi = rc.arm_upper[i], v = rc.arm_velocity[i];
    if (hi - lo > p.max_joint_range)
      r.problem("joint limits", "joint " + name + ": range [" + num(lo) + ", " + num(hi) +
                                    "] rad is more than two turns either way (robot.arm.lower / upper)");
    if (v < p.min_joint_velocity || v > p.max_joint_velocity)
      r.problem("joint limits", "joint " + name + ": velocity " + num(v) + " rad/s is outside the plausible " +
                                    num(p.min_joint_velocity, 2) + " .. " + num(p.max_joint_velocity, 1) +
                                    " rad/s (robot.arm.velocity, rad/s not deg/s)");
    const urdf::JointConstSharedPtr j = urdf.getJoint(name);
    if (j && j->type != urdf::Joint::CONTINUOUS && j->limits) {
      if (lo < j->limits->lower - 1e-9 || hi > j->limits->upper + 1e-9)
        r.problem("joint limits", "joint " + name + ": robot.arm limits [" + num(lo) + ", " + num(hi) +
                                      "] are wider than the URDF's [" + num(j->limits->lower) + ", " +
                                      num(j->limits->upper) + "]");
      if (j->limits->velocity > 0 && v > j->limits->velocity + 1e-9)
        r.problem("joint limits", "joint " + name + ": robot.arm.velocity " + num(v) + " exceeds the URDF's " +
                                      num(j->limits->velocity));
    }
    const double margin = std::min(rc.arm_ready[i] - lo, hi - rc.arm_ready[i]);
    least_margin = std::min(least_margin, margin);
    if (margin < p.ready_margin)
      r.problem("ready pose", "joint " + name + " is " + num(margin) + " rad from its limit in robot.arm.ready, closer than the "
                                  "controller's joint stop (" + num(p.ready_margin, 2) + " rad): move it inwards");
  }
  if (!r.problemsSince(mark))
    r.ok("joint limits", "ranges and velocities (" + num(rc.arm_velocity.minCoeff(), 2) + " .. " +
                             num(rc.arm_velocity.maxCoeff(), 2) + " rad/s) plausible; the ready pose is at least " +
                             num(least_margin, 2) + " rad inside every limit");
}

/// The camera and the gripper hang below the last arm joint; two finger joints of one travel.
/// Returns the robot's collision model (checkFingerPads reads it), nullptr where there is none.
std::unique_ptr<RobotCollisionModel> checkHand(const RobotConfig& rc, const std::string& xml,
                                               const urdf::ModelInterface& urdf, Report& r) {
  // An arm joint the URDF lacks is reported by the arm chain check (and would make the URDF's
  // joint of that name an unexplained movable joint here).
  for (const std::string& name : rc.arm_joints)
    if (!urdf.getJoint(name)) return nullptr;
  const urdf::JointConstSharedPtr last = urdf.getJoint(rc.arm_joints.back());
  const std::string hand = last->child_link_name;
  if (urdf.getLink(rc.camera_frame) && !hangsBelow(urdf, rc.camera_frame, hand))
    r.problem("camera mount", "the camera frame '" + rc.camera_frame + "' does not move with the last arm joint '" +
                                  last->name + "': mount the hand camera on the hand (below link '" + hand + "')");
  else if (urdf.getLink(rc.camera_frame))
    r.ok("camera mount", rc.camera_frame + " moves with the hand (below " + hand + ")");
  std::unique_ptr<RobotCollisionModel> collision;
  try {
    collision = std::make_unique<RobotCollisionModel>(xml, rc.arm_joints);
  } catch (const std::exception& e) {
    r.problem("collision geometry", e.what());
    return nullptr;
  }
  const auto& fingers = collision->fingers();
  std::string names;
  for (const FingerJoint& f : fingers) names += (names.empty() ? "" : ", ") + f.joint;
  if (fingers.size() != 2) {
    r.problem("fingers", "the gripper needs exactly two prismatic finger joints (found " + std::to_string(fingers.size()) +
                             (names.empty() ? "" : ": " + names) + "); the simulator drives them and the obstacle "
                             "field poses them open");
    return collision;
  }
  const std::size_t mark = r.size();
  for (const FingerJoint& f : fingers) {
    if (std::abs(f.lower) > 1e-9 || std::abs(f.upper - fingers.front().upper) > 1e-9)
      r.problem("fingers", "finger joint '" + f.joint + "': travel [" + num(f.lower, 4) + ", " + num(f.upper, 4) +
                               "] m; both fingers need the same travel from 0 (closed)");
    if (!hangsBelow(urdf, f.parent_link, hand))
      r.problem("fingers", "finger joint '" + f.joint + "' does not move with the last arm joint '" + last->name + "'");
  }
  if (!r.problemsSince(mark))
    r.ok("fingers", names + ": 0 .. " + num(fingers.front().upper, 4) + " m each, on the hand");
  return collision;
}

/// The fingers' pads, each finger's geometry's face towards the TCP along its closing axis (the
/// TCP's y), lie on the TCP when closed (opening 0), one finger on each side, and reach the TCP's
/// depth: the pads are 2 x opening apart about the TCP, as the grasp generator places a grasp's
/// contacts (pads that stay apart when closed close around a thinner wall or handle on nothing).
void checkFingerPads(const RobotConfig& rc, const RobotCollisionModel* collision, const WholeBodyModel& model,
                     Report& r) {
  if (!collision || collision->fingers().size() != 2) return;  // reported by checkHand
  const Eigen::Isometry3d tcp_inv = model.linkPoseInBase(rc.arm_ready, rc.tcp_frame).inverse();
  const std::size_t mark = r.size();
  std::vector<double> pads;
  for (const FingerJoint& f : collision->fingers()) {
    const auto link = std::find_if(collision->links().begin(), collision->links().end(),
                                   [&](const RobotLinkGeometry& l) { return l.name == f.child_link; });
    if (link == collision->links().end()) continue;  // no geometry: nothing to touch with
    const Eigen::Isometry3d finger = tcp_inv * model.linkPoseInBase(rc.arm_ready, f.child_link);
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e9), hi = -lo;  // extent in the TCP frame
    for (const CollisionShape& shape : link->shapes)
      for (int c = 0; c < 8; ++c) {
        const Eigen::Vector3d corner(c & 1 ? 1 : -1, c & 2 ? 1 : -1, c & 4 ? 1 : -1);
        const Eigen::Vector3d p = finger * shape.origin * shape.halfExtents().cwiseProduct(corner);
        lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
      }
    const double pad = lo.y() >= -1e-4 ? lo.y() : hi.y() <= 1e-4 ? hi.y() : NAN;
    if (std::isnan(pad))
      r.problem("fingers", "finger '" + f.child_link + "' reaches across the TCP's closing axis (y " + num(lo.y(), 4) +
                               " .. " + num(hi.y(), 4) + " m in the TCP frame) when closed: one finger on each side");
    else if (std::abs(pad) > 1e-4)
      r.problem("fingers", "finger '" + f.child_link + "': its pad lies " + num(std::abs(pad), 4) +
                               " m from the TCP when closed; the pads must touch there (2 x opening apart), or a "
                               "thinner wall or handle between them is closed on without being held");
    else
      pads.push_back(lo.y() >= -1e-4 ? 1.0 : -1.0);
    if (lo.z() > 0.0 || hi.z() < 0.0)
      r.problem("fingers", "finger '" + f.child_link + "' spans " + num(lo.z(), 4) + " .. " + num(hi.z(), 4) +
                               " m along the approach axis: its pad must reach the TCP's depth (0)");
  }
  if (pads.size() == 2 && pads[0] == pads[1])
    r.problem("fingers", "both fingers' pads lie on the same side of the TCP's closing axis");
  if (!r.problemsSince(mark))
    r.ok("fingers", "the pads touch at the TCP when closed (2 x opening apart)");
}

/// Where a corner of the view region lands in the image, or why it does not.
std::string cornerProblem(const PinholeCamera& cam, const Eigen::Vector3d& p_cam, const RobotCheckParams& p) {
  if (p_cam.z() <= cam.min_depth) return "behind the camera";
  if (p_cam.norm() > p.view_max_distance) return num(p_cam.norm(), 2) + " m away, beyond " + num(p.view_max_distance, 1) + " m";
  const Eigen::Vector2d uv = cam.pixel(p_cam);
  const double m = p.image_margin_px;
  if (uv.x() < m || uv.y() < m || uv.x() > cam.width - m || uv.y() > cam.height - m)
    return "at pixel (" + num(uv.x(), 0) + ", " + num(uv.y(), 0) + "), outside the " + std::to_string(cam.width) + " x " +
           std::to_string(cam.height) + " image";
  return "";
}

void checkCameraView(const RobotConfig& rc, const WholeBodyModel& model, const RobotCheckParams& p, Report& r) {
  PinholeCamera cam;
  if (!rc.camera_info_path.empty()) {
    try {
      cam = loadPinholeCamera(rc.camera_info_path);
    } catch (const std::exception& e) {
      r.problem("camera", e.what());
      return;
    }
  }
  const Eigen::Isometry3d T = model.fk(Eigen::Vector3d::Zero(), rc.arm_ready, rc.camera_frame);
  const Eigen::Vector3d axis = T.linear().col(2);
  const double azimuth = std::atan2(axis.y(), axis.x()) * 180.0 / M_PI;
  const std::string where = "in the ready pose the camera at " + vec(T.translation()) + " m looks " +
                            num(-std::asin(std::clamp(axis.z(), -1.0, 1.0)) * 180.0 / M_PI, 0) + " deg below the horizon and " +
                            num(std::abs(azimuth), 0) + " deg " + (azimuth < 0 ? "right" : "left") + " of ahead";
  int unseen = 0;
  std::string first;
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3d corner((c & 1) ? p.view_max.x() : p.view_min.x(), (c & 2) ? p.view_max.y() : p.view_min.y(),
                                 (c & 4) ? p.view_max.z() : p.view_min.z());
    const std::string why = cornerProblem(cam, T.inverse() * corner, p);
    if (why.empty()) continue;
    if (unseen++ == 0) first = "corner " + vec(corner, 3) + " is " + why;
  }
  const std::string region = "the region ahead (x " + num(p.view_min.x()) + " .. " + num(p.view_max.x()) + ", y " +
                             num(p.view_min.y()) + " .. " + num(p.view_max.y()) + ", z " + num(p.view_min.z()) + " .. " +
                             num(p.view_max.z()) + " m from the base at the start)";
  if (unseen > 0)
    r.problem("camera view", where + "; " + std::to_string(unseen) + " of 8 corners of " + region + " are not in its image (" +
                                 first + "): the hand camera will not see the scene; change robot.arm.ready");
  else
    r.ok("camera view", where + "; it sees " + region);
}

void checkMap(const RobotConfig& rc, const WholeBodyModel& model, Report& r) {
  if (rc.reachability_map_path.empty()) {
    r.problem("reachability map", "robot.yaml names none (robot.reachability_map): the ehc mode and MPBS need one; build it: " +
                                      rebuildCommand(rc));
    return;
  }
  std::string rebuild = "rebuild it: " + rebuildCommand(rc);
  try {
    const ReachabilityMap map = ReachabilityMap::load(rc.reachability_map_path);
    rebuild = "rebuild it: " + rebuildCommand(rc, &map);
    map.checkCompatible(rc);
    if (!map.hasKinematics()) {
      r.problem("reachability map", "'" + rc.reachability_map_path + "' records no kinematics of its arm (an older format), "
                                    "so nothing tells whether it is this arm's; " + rebuild);
      return;
    }
    const std::string mismatch = map.kinematicMismatch(model);
    if (!mismatch.empty()) {
      r.problem("reachability map", "'" + rc.reachability_map_path + "' was built for another arm: " + mismatch + "; " + rebuild);
      return;
    }
    r.ok("reachability map", "matches the arm (limits and TCP at " + std::to_string(map.referencePoses().size()) +
                                 " reference configurations): " + std::to_string(map.countAbove(0.0)) + " voxels reached, " +
                                 std::to_string(map.samples()) + " samples");
  } catch (const std::exception& e) {
    r.problem("reachability map", std::string(e.what()) + "; " + rebuild);
  }
}

}  // namespace

RobotCheckParams::RobotCheckParams() : ready_margin(QpControllerParams{}.joint_stop) {}

void RobotCheckParams::validate() const {
  if (!view_min.allFinite() || !view_max.allFinite() || (view_min.array() > view_max.array()).any())
    throw std::invalid_argument(std::string("[") + kOwner + "] the view region needs finite min <= max corners");
  ehc_common::requireRange(kOwner, "view_max_distance", view_max_distance, 0.1, 100.0);
  ehc_common::requireRange(kOwner, "image_margin_px", image_margin_px, 0.0, 1000.0);
  ehc_common::requireRange(kOwner, "min_joint_velocity", min_joint_velocity, 0.0, max_joint_velocity);
  ehc_common::requireRange(kOwner, "max_joint_velocity", max_joint_velocity, min_joint_velocity, 1000.0);
  ehc_common::requireRange(kOwner, "max_joint_range", max_joint_range, 0.0, 1000.0);
  ehc_common::requireRange(kOwner, "ready_margin", ready_margin, 0.0, 3.2);
}

std::vector<RobotCheckLine> checkRobot(const std::string& robot_file, const RobotCheckParams& params) {
  params.validate();
  Report r;
  RobotConfig rc;
  try {
    rc = loadRobotConfig(robot_file);
  } catch (const std::exception& e) {
    r.problem("robot.yaml", e.what());
    return r.take();
  }
  r.ok("robot.yaml", "robot '" + rc.name + "': " + std::to_string(rc.nArm()) + " arm joints, " + toString(rc.base_type) +
                         " base (" + robot_file + ")");
  std::string xml;
  try {
    xml = readUrdfFile(rc.urdf_path);
  } catch (const std::exception& e) {
    r.problem("urdf", std::string(e.what()) + " (robot.urdf)");
    return r.take();
  }
  const urdf::ModelInterfaceSharedPtr urdf = urdf::parseURDF(xml);
  if (!urdf) {
    r.problem("urdf", "'" + rc.urdf_path + "' does not parse as a URDF (robot.urdf)");
    return r.take();
  }
  checkFrames(rc, *urdf, r);
  checkArmChain(rc, *urdf, r);
  checkJointLimits(rc, *urdf, params, r);
  const std::unique_ptr<RobotCollisionModel> collision = checkHand(rc, xml, *urdf, r);
  std::unique_ptr<WholeBodyModel> model;
  try {
    model = std::make_unique<WholeBodyModel>(rc);
  } catch (const std::exception& e) {
    // The lines above already say why, unless the model found something they do not check.
    if (!r.problemsSince(0)) r.problem("kinematic model", e.what());
    return r.take();
  }
  checkFingerPads(rc, collision.get(), *model, r);
  checkCameraView(rc, *model, params, r);
  checkMap(rc, *model, r);
  return r.take();
}

bool allOk(const std::vector<RobotCheckLine>& lines) {
  return std::all_of(lines.begin(), lines.end(), [](const RobotCheckLine& l) { return l.ok; });
}

std::string toString(const RobotCheckLine& line) {
  return std::string(line.ok ? "ok " : "PROBLEM ") + line.check + ": " + line.message;
}

}  // namespace ehc_control
