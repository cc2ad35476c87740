#include "ehc_control/whole_body_model.h"

#include <kdl/chain.hpp>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainiksolverpos_nr_jl.hpp>
#include <kdl/chainiksolvervel_pinv.hpp>
#include <kdl/chainjnttojacsolver.hpp>
#include <kdl/tree.hpp>
#include <kdl_parser/kdl_parser.hpp>
#include <tinyxml.h>
#include <urdf_parser/urdf_parser.h>

#include <Eigen/Cholesky>
#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <map>
#include <memory>
#include <random>
#include <sstream>
#include <stdexcept>

namespace ehc_control {

namespace {
[[noreturn]] void fail(const std::string& what) {
  throw std::invalid_argument("[WholeBodyModel] " + what);
}

/// robot.yaml's field `field` does not match the URDF: names the file and the field.
[[noreturn]] void failField(const RobotConfig& cfg, const std::string& field, const std::string& what) {
  fail((cfg.source_file.empty() ? std::string("robot config") : cfg.source_file) + ": field '" + field + "' " + what +
       " (URDF " + cfg.urdf_path + ")");
}

/// The URDF robot.yaml names; an unreadable file names the field.
std::string urdfOf(const RobotConfig& cfg) {
  if (!std::ifstream(cfg.urdf_path)) failField(cfg, "robot.urdf", "names a file that cannot be read");
  return readUrdfFile(cfg.urdf_path);
}

Eigen::Isometry3d toEigen(const KDL::Frame& f) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  for (int r = 0; r < 3; ++r) {
    t.translation()[r] = f.p[r];
    for (int c = 0; c < 3; ++c) t.linear()(r, c) = f.M(r, c);
  }
  return t;
}

/// Base columns of a world-frame whole-body Jacobian of a point at r (world, from the base
/// origin): v_x (, v_y) move the point along the base axes, w_z turns it about the base z axis.
void setBaseColumns(BaseType type, const Eigen::Matrix3d& world_R_base, const Eigen::Vector3d& r,
                    Matrix6Xd* J) {
  J->leftCols(type == BaseType::Holonomic ? 3 : 2).setZero();
  J->block<3, 1>(0, 0) = world_R_base.col(0);  // v_x
  int wz = 1;
  if (type == BaseType::Holonomic) {
    J->block<3, 1>(0, 1) = world_R_base.col(1);  // v_y
    wz = 2;
  }
  J->block<3, 1>(0, wz) = Eigen::Vector3d::UnitZ().cross(r);  // w_z
  (*J)(5, wz) = 1.0;
}
}  // namespace

/// One kinematic chain from the base link to a link, with its joints mapped to arm indices.
struct LinkChain {
  KDL::Chain chain;
  std::vector<int> arm_index;  ///< per movable chain joint: arm joint index, -1 = held at 0
  std::unique_ptr<KDL::ChainFkSolverPos_recursive> fk;
  std::unique_ptr<KDL::ChainJntToJacSolver> jac;
  mutable KDL::JntArray q;
  mutable KDL::Jacobian J;
};

/// One link of the kinematic tree for the one-pass forward kinematics (updateKinematics).
/// Its pose relative to the parent link: revolute  Trans(o) Rot(axis, q) Trans(-o) tip0,
/// prismatic  Trans(axis q) tip0, fixed (or a movable joint that is no arm joint, held at 0)
/// tip0, with tip0 the pose at q = 0 and o a point on the joint axis (KDL Joint::pose; o = 0
/// unless revolute).
struct TreeLink {
  enum class Joint { Fixed, Revolute, Prismatic };
  int parent = -1;     ///< tree index of the parent link; -1: the root (base frame)
  Joint joint = Joint::Fixed;
  int arm_index = -1;  ///< arm joint of a revolute/prismatic link
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();  ///< unit joint axis, parent frame
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  ///< revolute: point o on the axis, parent frame
  Eigen::Matrix3d tip_rotation = Eigen::Matrix3d::Identity();  ///< rotation of tip0
  Eigen::Vector3d tip_offset = Eigen::Vector3d::Zero();        ///< translation of tip0 - o
  std::vector<int> arm_joints;  ///< arm joints between the root and this link, root first
};

namespace {
/// Pose of a tree link in its parent's frame for joint position q.
Eigen::Isometry3d childPose(const TreeLink& l, double q) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  switch (l.joint) {
    case TreeLink::Joint::Revolute: {
      const Eigen::Matrix3d R = Eigen::AngleAxisd(q, l.axis).toRotationMatrix();
      t.linear() = R * l.tip_rotation;
      t.translation() = l.origin + R * l.tip_offset;
      break;
    }
    case TreeLink::Joint::Prismatic:
      t.linear() = l.tip_rotation;
      t.translation() = l.tip_offset + q * l.axis;
      break;
    case TreeLink::Joint::Fixed:
      t.linear() = l.tip_rotation;
      t.translation() = l.tip_offset;
      break;
  }
  return t;
}
}  // namespace

struct WholeBodyModel::Impl {
  std::map<std::string, std::unique_ptr<LinkChain>> links;
  std::vector<bool> arm_revolute;
  const LinkChain* tcp = nullptr;
  std::vector<TreeLink> tree;                ///< parents before children
  std::map<std::string, int> tree_index;     ///< link name -> tree index

  void buildTree(const KDL::Tree& kdl_tree, const std::map<std::string, int>& arm_idx);

  const LinkChain& chain(const std::string& link) const {
    const auto it = links.find(link);
    if (it == links.end()) fail("unknown link '" + link + "'");
    return *it->second;
  }
  void load(const LinkChain& lc, const Eigen::VectorXd& q) const {
    for (std::size_t i = 0; i < lc.arm_index.size(); ++i)
      lc.q(static_cast<unsigned>(i)) = lc.arm_index[i] >= 0 ? q[lc.arm_index[i]] : 0.0;
  }
};

std::string readUrdfFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) fail("cannot read URDF file '" + path + "'");
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

WholeBodyModel::WholeBodyModel(const RobotConfig& cfg) : WholeBodyModel(cfg, urdfOf(cfg)) {}

WholeBodyModel::WholeBodyModel(const RobotConfig& cfg, const std::string& urdf_xml)
    : cfg_(cfg), urdf_xml_(urdf_xml), impl_(std::make_unique<Impl>()) {
  try {
    cfg_.validate();
  } catch (const std::invalid_argument& e) {
    fail(std::string("invalid robot config: ") + e.what());
  }
  build();
}

WholeBodyModel::~WholeBodyModel() = default;
WholeBodyModel::WholeBodyModel(WholeBodyModel&&) noexcept = default;
WholeBodyModel& WholeBodyModel::operator=(WholeBodyModel&&) noexcept = default;

namespace {
/// The URDF with the calibration of `cfg` applied to its fixed joints (the one place it is done).
urdf::ModelInterfaceSharedPtr parseCalibrated(const RobotConfig& cfg, const std::string& xml) {
  const urdf::ModelInterfaceSharedPtr model = urdf::parseURDF(xml);
  if (!model) failField(cfg, "robot.urdf", "names a URDF that could not be parsed (see the message above)");
  for (const FrameOverride& o : cfg.calibration) {
    const auto it = model->joints_.find(o.joint);
    const std::string field = "robot.calibration." + o.key + ".joint";
    if (it == model->joints_.end()) failField(cfg, field, "names joint '" + o.joint + "' which is not in the URDF");
    if (it->second->type != urdf::Joint::FIXED) failField(cfg, field, "names joint '" + o.joint + "', which must be a fixed joint");
    urdf::Pose& p = it->second->parent_to_joint_origin_transform;
    p.position = urdf::Vector3(o.xyz.x(), o.xyz.y(), o.xyz.z());
    p.rotation.setFromRPY(o.rpy.x(), o.rpy.y(), o.rpy.z());
  }
  return model;
}
}  // namespace

std::string WholeBodyModel::calibratedUrdfXml() const {
  parseCalibrated(cfg_, urdf_xml_);  // the checks (joints exist, are fixed)
  // The original text with the <origin> of each calibrated joint replaced (full precision;
  // urdfdom's exporter rounds to 6 digits, which would make limits and frames drift).
  TiXmlDocument doc;
  doc.Parse(urdf_xml_.c_str());
  if (doc.Error()) fail("URDF of '" + cfg_.urdf_path + "' could not be parsed: " + doc.ErrorDesc());
  TiXmlElement* robot = doc.RootElement();
  auto triple = [](const Eigen::Vector3d& v) {
    std::ostringstream os;
    os << std::setprecision(17) << v.x() << " " << v.y() << " " << v.z();
    return os.str();
  };
  for (const FrameOverride& o : cfg_.calibration) {
    TiXmlElement* joint = robot ? robot->FirstChildElement("joint") : nullptr;
    while (joint && (!joint->Attribute("name") || o.joint != joint->Attribute("name")))
      joint = joint->NextSiblingElement("joint");
    if (!joint) failField(cfg_, "robot.calibration." + o.key + ".joint", "names joint '" + o.joint + "' which is not in the URDF");
    TiXmlElement* origin = joint->FirstChildElement("origin");
    if (!origin) origin = joint->InsertEndChild(TiXmlElement("origin"))->ToElement();
    origin->SetAttribute("xyz", triple(o.xyz));
    origin->SetAttribute("rpy", triple(o.rpy));
  }
  TiXmlPrinter printer;
  printer.SetIndent("  ");
  doc.Accept(&printer);
  return printer.Str();
}

void WholeBodyModel::build() {
  const urdf::ModelInterfaceSharedPtr model = parseCalibrated(cfg_, urdf_xml_);

  const std::string root = model->getRoot() ? model->getRoot()->name : "";
  if (root != cfg_.base_frame)
    failField(cfg_, "robot.frames.base", "is '" + cfg_.base_frame + "' but the URDF's root link is '" + root + "'");

  KDL::Tree tree;
  if (!kdl_parser::treeFromUrdfModel(*model, tree)) fail("kdl_parser could not build a KDL tree");

  // Arm joints: exist, are revolute/prismatic, limits inside the URDF's.
  std::map<std::string, int> arm_idx;
  impl_->arm_revolute.assign(static_cast<std::size_t>(nArm()), true);
  for (int i = 0; i < nArm(); ++i) {
    const std::string& name = cfg_.arm_joints[static_cast<std::size_t>(i)];
    const auto it = model->joints_.find(name);
    if (it == model->joints_.end()) failField(cfg_, "robot.arm.joints", "names joint '" + name + "' which is not in the URDF");
    const urdf::Joint& j = *it->second;
    if (j.type == urdf::Joint::PRISMATIC)
      impl_->arm_revolute[static_cast<std::size_t>(i)] = false;
    else if (j.type != urdf::Joint::REVOLUTE && j.type != urdf::Joint::CONTINUOUS)
      failField(cfg_, "robot.arm.joints", "names joint '" + name + "', which must be revolute, continuous or prismatic");
    if (j.type != urdf::Joint::CONTINUOUS && j.limits) {
      const double eps = 1e-9;
      if (cfg_.arm_lower[i] < j.limits->lower - eps || cfg_.arm_upper[i] > j.limits->upper + eps)
        failField(cfg_, "robot.arm.lower/upper", "of joint '" + name + "' are wider than the URDF's limits");
      if (j.limits->velocity > 0 && cfg_.arm_velocity[i] > j.limits->velocity + eps)
        failField(cfg_, "robot.arm.velocity", "of joint '" + name + "' exceeds the URDF's limit");
    }
    arm_idx[name] = i;
  }

  for (const auto& seg : tree.getSegments()) {
    const std::string& link = seg.first;
    auto lc = std::make_unique<LinkChain>();
    if (link != root && !tree.getChain(root, link, lc->chain)) continue;
    for (const auto& s : lc->chain.segments) {
      if (s.getJoint().getType() == KDL::Joint::None) continue;
      const auto it = arm_idx.find(s.getJoint().getName());
      lc->arm_index.push_back(it == arm_idx.end() ? -1 : it->second);
    }
    lc->fk = std::make_unique<KDL::ChainFkSolverPos_recursive>(lc->chain);
    lc->jac = std::make_unique<KDL::ChainJntToJacSolver>(lc->chain);
    lc->q.resize(lc->chain.getNrOfJoints());
    lc->J.resize(lc->chain.getNrOfJoints());
    impl_->links[link] = std::move(lc);
  }

  for (const auto& [f, field] : {std::make_pair(cfg_.arm_base_frame, "robot.frames.arm_base"),
                                 std::make_pair(cfg_.tcp_frame, "robot.frames.tcp"),
                                 std::make_pair(cfg_.camera_frame, "robot.frames.camera_optical")})
    if (!impl_->links.count(f)) failField(cfg_, field, "names link '" + f + "' which is not in the URDF");
  // Every link robot.yaml names must be a link of the URDF (never silently ignored).
  auto requireLink = [&](const std::string& link, const std::string& field) {
    if (!impl_->links.count(link)) failField(cfg_, field, "names link '" + link + "' which is not in the URDF");
  };
  for (const std::string& l : cfg_.checked_links) requireLink(l, "robot.collision.checked_links");
  for (const std::string& l : cfg_.floor_links) requireLink(l, "robot.collision.floor_links");
  for (const auto& [a, b] : cfg_.ignore_pairs) {
    requireLink(a, "robot.collision.ignore_pairs");
    requireLink(b, "robot.collision.ignore_pairs");
  }
  for (const auto& kv : cfg_.obstacle_stop_distances) requireLink(kv.first, "robot.obstacle_stop_distances");

  // The TCP chain must contain exactly the arm joints, in the configured order.
  const LinkChain& tcp = *impl_->links.at(cfg_.tcp_frame);
  std::vector<int> expected;
  for (int i = 0; i < nArm(); ++i) expected.push_back(i);
  if (tcp.arm_index != expected) {
    std::string chain_joints;
    for (const auto& s : tcp.chain.segments)
      if (s.getJoint().getType() != KDL::Joint::None) chain_joints += s.getJoint().getName() + " ";
    failField(cfg_, "robot.arm.joints", "must be the movable joints from '" + cfg_.base_frame + "' to '" + cfg_.tcp_frame +
                                            "' in order; the URDF chain has: " + chain_joints);
  }
  impl_->tcp = &tcp;
  impl_->buildTree(tree, arm_idx);
}

void WholeBodyModel::Impl::buildTree(const KDL::Tree& kdl_tree, const std::map<std::string, int>& arm_idx) {
  // Depth-first from the root: every link after its parent.
  std::vector<std::pair<KDL::SegmentMap::const_iterator, int>> todo{{kdl_tree.getRootSegment(), -1}};
  while (!todo.empty()) {
    const auto [it, parent] = todo.back();
    todo.pop_back();
    TreeLink l;
    l.parent = parent;
    if (parent >= 0) {
      const KDL::Segment& seg = GetTreeElementSegment(it->second);
      const KDL::Joint& j = seg.getJoint();
      const auto a = arm_idx.find(j.getName());
      const bool movable = j.getType() != KDL::Joint::None && a != arm_idx.end();
      const KDL::Frame tip0 = seg.pose(0.0);
      for (int r = 0; r < 3; ++r) {
        l.tip_offset[r] = tip0.p[r];
        for (int c = 0; c < 3; ++c) l.tip_rotation(r, c) = tip0.M(r, c);
      }
      l.arm_joints = tree[static_cast<std::size_t>(parent)].arm_joints;
      if (movable) {
        const bool revolute = arm_revolute[static_cast<std::size_t>(a->second)];
        l.joint = revolute ? TreeLink::Joint::Revolute : TreeLink::Joint::Prismatic;
        l.arm_index = a->second;
        l.arm_joints.push_back(a->second);
        l.axis = Eigen::Vector3d(j.JointAxis()[0], j.JointAxis()[1], j.JointAxis()[2]);
        if (!(l.axis.norm() > 0.0)) fail("joint '" + j.getName() + "' has a zero axis");
        l.axis.normalize();
        if (revolute) {
          l.origin = Eigen::Vector3d(j.JointOrigin()[0], j.JointOrigin()[1], j.JointOrigin()[2]);
          l.tip_offset -= l.origin;
        }
        // The pose model above is KDL's for unscaled joints without offset (kdl_parser's);
        // refuse anything else rather than silently differ from the KDL chains.
        const double q = 0.7;
        const KDL::Frame f = seg.pose(q);
        const Eigen::Isometry3d mine = childPose(l, q);
        for (int r = 0; r < 3; ++r) {
          bool same = std::abs(mine.translation()[r] - f.p[r]) < 1e-12;
          for (int c = 0; c < 3; ++c) same &= std::abs(mine.linear()(r, c) - f.M(r, c)) < 1e-12;
          if (!same) fail("joint '" + j.getName() + "': unsupported KDL joint (scale or offset)");
        }
      }
    }
    const int index = static_cast<int>(tree.size());
    tree_index[it->first] = index;
    tree.push_back(std::move(l));
    for (const auto& child : GetTreeElementChildren(it->second)) todo.emplace_back(child, index);
  }
}

std::vector<std::string> WholeBodyModel::dofNames() const {
  std::vector<std::string> n{"base_vx"};
  if (baseType() == BaseType::Holonomic) n.push_back("base_vy");
  n.push_back("base_wz");
  n.insert(n.end(), cfg_.arm_joints.begin(), cfg_.arm_joints.end());
  return n;
}

std::vector<std::string> WholeBodyModel::linkNames() const {
  std::vector<std::string> out;
  for (const auto& l : impl_->links) out.push_back(l.first);
  return out;
}

bool WholeBodyModel::hasLink(const std::string& link) const { return impl_->links.count(link) > 0; }

Eigen::Isometry3d WholeBodyModel::baseTransform(const Eigen::Vector3d& b) {
  checkBase(b);
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() << b.x(), b.y(), 0.0;
  t.linear() = Eigen::AngleAxisd(b.z(), Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return t;
}

void WholeBodyModel::checkArm(const Eigen::VectorXd& q) const {
  if (q.size() != nArm())
    fail("expected " + std::to_string(nArm()) + " arm joint positions, got " +
         std::to_string(q.size()));
  if (!q.allFinite()) fail("arm joint positions contain NaN or Inf");
}

void WholeBodyModel::checkBase(const Eigen::Vector3d& b) {
  if (!b.allFinite()) fail("base pose (x, y, yaw) contains NaN or Inf");
}

Eigen::VectorXd WholeBodyModel::clampToLimits(const Eigen::VectorXd& q) const {
  checkArm(q);
  return q.cwiseMax(cfg_.arm_lower).cwiseMin(cfg_.arm_upper);
}

Eigen::Isometry3d WholeBodyModel::linkPoseInBase(const Eigen::VectorXd& q,
                                                 const std::string& link) const {
  checkArm(q);
  const LinkChain& lc = impl_->chain(link);
  impl_->load(lc, q);
  KDL::Frame f;
  if (lc.fk->JntToCart(lc.q, f) < 0) fail("KDL forward kinematics failed for link '" + link + "'");
  return toEigen(f);
}

Eigen::Isometry3d WholeBodyModel::fk(const Eigen::Vector3d& base_pose, const Eigen::VectorXd& q,
                                     const std::string& link) const {
  return baseTransform(base_pose) * linkPoseInBase(q, link);
}

Matrix6Xd WholeBodyModel::armJacobian(const Eigen::VectorXd& q, const std::string& link) const {
  checkArm(q);
  const LinkChain& lc = impl_->chain(link);
  impl_->load(lc, q);
  if (lc.jac->JntToJac(lc.q, lc.J) < 0) fail("KDL Jacobian failed for link '" + link + "'");
  Matrix6Xd J = Matrix6Xd::Zero(6, nArm());
  for (std::size_t c = 0; c < lc.arm_index.size(); ++c)
    if (lc.arm_index[c] >= 0) J.col(lc.arm_index[c]) = lc.J.data.col(static_cast<int>(c));
  return J;
}

Matrix6Xd WholeBodyModel::jacobian(const Eigen::Vector3d& base_pose, const Eigen::VectorXd& q,
                                   const std::string& link, Eigen::Isometry3d* pose,
                                   Matrix6Xd* arm_jacobian) const {
  const Eigen::Isometry3d Twb = baseTransform(base_pose);
  const Eigen::Isometry3d Tbl = linkPoseInBase(q, link);
  const Matrix6Xd Ja = armJacobian(q, link);
  const Eigen::Matrix3d R = Twb.linear();
  const Eigen::Vector3d r = R * Tbl.translation();  // base origin -> link origin, world
  const int nb = nBase();
  Matrix6Xd J(6, nDof());
  setBaseColumns(baseType(), R, r, &J);  // base frame velocities mapped to the link origin
  J.block(0, nb, 3, nArm()) = R * Ja.topRows<3>();
  J.block(3, nb, 3, nArm()) = R * Ja.bottomRows<3>();
  if (pose) *pose = Twb * Tbl;
  if (arm_jacobian) *arm_jacobian = Ja;
  return J;
}

int WholeBodyModel::linkIndex(const std::string& link) const {
  const auto it = impl_->tree_index.find(link);
  if (it == impl_->tree_index.end()) fail("unknown link '" + link + "'");
  return it->second;
}

void WholeBodyModel::updateKinematics(const Eigen::Vector3d& base_pose, const Eigen::VectorXd& q,
                                      KinematicState* s) const {
  checkArm(q);
  s->world_T_base_ = baseTransform(base_pose);
  const std::vector<TreeLink>& tree = impl_->tree;
  s->base_T_link_.resize(tree.size());
  s->joint_axis_.resize(3, nArm());
  s->joint_point_.resize(3, nArm());
  for (std::size_t i = 0; i < tree.size(); ++i) {
    const TreeLink& l = tree[i];
    Eigen::Isometry3d& T = s->base_T_link_[i];
    if (l.parent < 0) {
      T.setIdentity();
      continue;
    }
    const Eigen::Isometry3d& P = s->base_T_link_[static_cast<std::size_t>(l.parent)];
    T = P * childPose(l, l.arm_index >= 0 ? q[l.arm_index] : 0.0);
    if (l.arm_index >= 0) {
      s->joint_axis_.col(l.arm_index) = P.linear() * l.axis;
      s->joint_point_.col(l.arm_index) = P * l.origin;
    }
  }
}


void WholeBodyModel::pointJacobianInBase(const KinematicState& s, int link, const Eigen::Vector3d& p,
                                         Matrix6Xd* J, Matrix6Xd* arm_jacobian) const {
  const int nb = nBase(), na = nArm();
  if (J->cols() != nDof()) J->resize(6, nDof());
  if (arm_jacobian) {
    if (arm_jacobian->cols() != na) arm_jacobian->resize(6, na);
    arm_jacobian->setZero();
  }
  const Eigen::Matrix3d& R = s.world_T_base_.linear();
  setBaseColumns(baseType(), R, R * p, J);
  J->rightCols(na).setZero();
  for (const int i : impl_->tree[static_cast<std::size_t>(link)].arm_joints) {
    const Eigen::Vector3d w = s.joint_axis_.col(i);
    Eigen::Matrix<double, 6, 1> col;  // base frame
    if (impl_->arm_revolute[static_cast<std::size_t>(i)]) {
      col << w.cross(p - s.joint_point_.col(i)), w;
    } else {
      col << w, Eigen::Vector3d::Zero();
    }
    if (arm_jacobian) arm_jacobian->col(i) = col;
    J->block<3, 1>(0, nb + i) = R * col.head<3>();
    J->block<3, 1>(3, nb + i) = R * col.tail<3>();
  }
}

void WholeBodyModel::jacobian(const KinematicState& s, int link, Matrix6Xd* J,
                              Matrix6Xd* arm_jacobian) const {
  pointJacobianInBase(s, link, s.linkPoseInBase(link).translation(), J, arm_jacobian);
}

void WholeBodyModel::pointJacobian(const KinematicState& s, int link, const Eigen::Vector3d& point_world,
                                   Matrix6Xd* J) const {
  pointJacobianInBase(s, link, s.world_T_base_.inverse() * point_world, J, nullptr);
}

double WholeBodyModel::manipulability(const Eigen::VectorXd& q) const {
  const Matrix6Xd J = armJacobian(q, cfg_.tcp_frame);
  const double d = nArm() >= 6 ? (J * J.transpose()).determinant()
                               : (J.transpose() * J).determinant();
  return std::sqrt(std::max(0.0, d));
}

Eigen::VectorXd WholeBodyModel::manipulabilityGradient(const Eigen::VectorXd& q, double* m_out) const {
  return manipulabilityGradientFromJacobian(armJacobian(q, cfg_.tcp_frame), m_out);
}

Eigen::VectorXd WholeBodyModel::manipulabilityGradientFromJacobian(const Matrix6Xd& J, double* m_out) const {
  Eigen::VectorXd g;
  manipulabilityGradientFromJacobian(J, g, m_out);
  return g;
}

void WholeBodyModel::manipulabilityGradientFromJacobian(const Matrix6Xd& J, Eigen::VectorXd& g,
                                                        double* m_out) const {
  const int n = nArm();
  if (J.cols() != n) fail("manipulabilityGradientFromJacobian: expected a 6 x " + std::to_string(n) + " arm Jacobian");
  // A = J J^T (n >= 6) or J^T J: at most 6 x 6, kept on the stack.
  using Small = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 6, 6>;
  const bool wide = n >= 6;
  Small A(wide ? 6 : n, wide ? 6 : n);
  if (wide)
    A.noalias() = J * J.transpose();
  else
    A.noalias() = J.transpose() * J;
  const double m = std::sqrt(std::max(0.0, A.determinant()));
  if (m_out) *m_out = m;
  if (g.size() != n) g.resize(n);
  g.setZero();
  if (!(m > 1e-12)) return;
  const Eigen::LDLT<Small> Ainv(A);
  const auto& rev = impl_->arm_revolute;
  // d m / d q_b = m tr(A^-1 dA_b) / 2 with dA_b = H_b J^T + J H_b^T (wide) or H_b^T J + J^T H_b,
  // H_b = dJ/dq_b (geometric Jacobian Hessian slice, base frame). With A symmetric this is
  // m <K, H_b> (sum of the entrywise products), K = A^-1 J (wide) or J A^-1: column a of K
  // meets column a of every H_b, so K is formed one column at a time.
  Small Ainv_dense;
  if (!wide) Ainv_dense = Ainv.solve(Small::Identity(n, n));
  for (int a = 0; a < n; ++a) {
    Eigen::Matrix<double, 6, 1> k;
    if (wide)
      k = Ainv.solve(J.col(a));
    else
      k = J * Ainv_dense.col(a);
    const Eigen::Vector3d va = J.block<3, 1>(0, a), wa = J.block<3, 1>(3, a);
    for (int b = 0; b < n; ++b) {
      if (b <= a) {  // column a of H_b: z_b x J_a (revolute b)
        if (!rev[static_cast<std::size_t>(b)]) continue;
        const Eigen::Vector3d zb = J.block<3, 1>(3, b);
        g[b] += k.head<3>().dot(zb.cross(va)) + k.tail<3>().dot(zb.cross(wa));
      } else if (rev[static_cast<std::size_t>(a)]) {  // [z_a x v_b; 0]
        g[b] += k.head<3>().dot(wa.cross(J.block<3, 1>(0, b)));
      }
    }
  }
  g *= m;
}

/// The whole-body IK problem of one target: a virtual planar base (prismatic x, prismatic y,
/// revolute yaw) followed by the TCP chain, the arm joints within their limits shrunk by the
/// margin, the base within 3 m of the target, KDL's Newton-Raphson solver with joint limits.
struct WholeBodyModel::IkProblem {
  KDL::Chain chain;
  unsigned n = 0;
  unsigned nb = 3;  ///< virtual base joints in the chain (0: the base held)
  KDL::JntArray lo, hi;
  KDL::Frame goal;
  Eigen::Isometry3d target;
  std::unique_ptr<KDL::ChainFkSolverPos_recursive> fk;
  std::unique_ptr<KDL::ChainIkSolverVel_pinv> ikv;
  std::unique_ptr<KDL::ChainIkSolverPos_NR_JL> ik;

  /// `held_base`: the base stays at that pose (x, y, yaw) and the arm alone solves; nullptr: the
  /// virtual planar base joints x, y, yaw are free.
  IkProblem(const WholeBodyModel& m, const Eigen::Isometry3d& T, double limit_margin,
            const Eigen::Vector3d* held_base = nullptr, unsigned iterations = 500)
      : target(T) {
    const RobotConfig& cfg = m.cfg_;
    if (!T.matrix().allFinite()) fail("inverseKinematics: target is not finite");
    if (!(limit_margin >= 0.0) || ((cfg.arm_upper - cfg.arm_lower).array() <= 2.0 * limit_margin).any())
      fail("inverseKinematics: limit margin must be >= 0 and leave every joint a range");
    if (held_base) {
      nb = 0;
      const Eigen::Isometry3d B = baseTransform(*held_base);
      KDL::Frame f;
      for (int r = 0; r < 3; ++r) {
        f.p[r] = B.translation()[r];
        for (int c = 0; c < 3; ++c) f.M(r, c) = B.linear()(r, c);
      }
      chain.addSegment(KDL::Segment(KDL::Joint(KDL::Joint::None), f));
    } else {
      chain.addSegment(KDL::Segment(KDL::Joint("virtual_x", KDL::Joint::TransX)));
      chain.addSegment(KDL::Segment(KDL::Joint("virtual_y", KDL::Joint::TransY)));
      chain.addSegment(KDL::Segment(KDL::Joint("virtual_yaw", KDL::Joint::RotZ)));
    }
    chain.addChain(m.impl_->tcp->chain);
    n = chain.getNrOfJoints();
    lo.resize(n);
    hi.resize(n);
    const Eigen::Vector3d t = T.translation();
    if (nb == 3) {
      for (unsigned i = 0; i < 2; ++i) {
        lo(i) = t[static_cast<int>(i)] - 3.0;
        hi(i) = t[static_cast<int>(i)] + 3.0;
      }
      lo(2) = -4.0 * M_PI;
      hi(2) = 4.0 * M_PI;
    }
    for (int i = 0; i < m.nArm(); ++i) {
      lo(nb + static_cast<unsigned>(i)) = cfg.arm_lower[i] + limit_margin;
      hi(nb + static_cast<unsigned>(i)) = cfg.arm_upper[i] - limit_margin;
    }
    fk = std::make_unique<KDL::ChainFkSolverPos_recursive>(chain);
    ikv = std::make_unique<KDL::ChainIkSolverVel_pinv>(chain);
    ik = std::make_unique<KDL::ChainIkSolverPos_NR_JL>(chain, lo, hi, *fk, *ikv, iterations, 1e-6);
    for (int r = 0; r < 3; ++r) {
      goal.p[r] = t[r];
      for (int c = 0; c < 3; ++c) goal.M(r, c) = T.linear()(r, c);
    }
  }

  /// One Newton-Raphson solve from q0 = [x, y, yaw, q_arm] (the base held: q_arm); true when the
  /// TCP reaches the target within 1 mm / 0.5 deg with every arm joint inside its (shrunk) range.
  bool solve(const KDL::JntArray& q0, Eigen::Vector3d* base_out, Eigen::VectorXd* q_out) const {
    KDL::JntArray qs(n);
    if (ik->CartToJnt(q0, goal, qs) < 0) return false;
    KDL::Frame f;
    fk->JntToCart(qs, f);
    const Eigen::Isometry3d T = toEigen(f);
    const Eigen::AngleAxisd d(Eigen::Matrix3d(T.linear().transpose() * target.linear()));
    if ((T.translation() - target.translation()).norm() > 1e-3 || std::abs(d.angle()) > 0.5 * M_PI / 180.0) return false;
    for (unsigned i = nb; i < n; ++i)
      if (qs(i) < lo(i) - 1e-9 || qs(i) > hi(i) + 1e-9) return false;
    if (base_out && nb == 3) *base_out = Eigen::Vector3d(qs(0), qs(1), std::remainder(qs(2), 2.0 * M_PI));
    if (q_out) {
      q_out->resize(static_cast<Eigen::Index>(n - nb));
      for (unsigned i = nb; i < n; ++i) (*q_out)[static_cast<Eigen::Index>(i - nb)] = qs(i);
    }
    return true;
  }
};

bool WholeBodyModel::inverseKinematics(const Eigen::Isometry3d& target, unsigned seed, int attempts,
                                       Eigen::Vector3d* base_out, Eigen::VectorXd* q_out, double limit_margin) const {
  const IkProblem p(*this, target, limit_margin);
  KDL::JntArray q0(p.n);
  const Eigen::Vector3d t = target.translation();
  std::mt19937_64 rng(seed);
  for (int a = 0; a < attempts; ++a) {
    for (unsigned i = 0; i < p.n; ++i) {
      std::uniform_real_distribution<double> u(p.lo(i), p.hi(i));
      q0(i) = u(rng);
    }
    // Start the base within arm's reach of the target, facing it.
    const double yaw = std::uniform_real_distribution<double>(-M_PI, M_PI)(rng);
    q0(0) = t.x() - 0.4 * std::cos(yaw);
    q0(1) = t.y() - 0.4 * std::sin(yaw);
    q0(2) = yaw;
    if (p.solve(q0, base_out, q_out)) return true;
  }
  return false;
}

bool WholeBodyModel::inverseKinematicsFrom(const Eigen::Isometry3d& target, const Eigen::Vector3d& base_start,
                                           const Eigen::VectorXd& q_start, Eigen::Vector3d* base_out,
                                           Eigen::VectorXd* q_out, double limit_margin) const {
  checkBase(base_start);
  checkArm(q_start);
  const IkProblem p(*this, target, limit_margin);
  KDL::JntArray q0(p.n);
  for (unsigned i = 0; i < 3; ++i) q0(i) = base_start[static_cast<int>(i)];
  for (unsigned i = 3; i < p.n; ++i)
    q0(i) = std::clamp(q_start[static_cast<Eigen::Index>(i - 3)], p.lo(i), p.hi(i));
  return p.solve(q0, base_out, q_out);
}

bool WholeBodyModel::armInverseKinematicsFrom(const Eigen::Isometry3d& target, const Eigen::Vector3d& base,
                                              const Eigen::VectorXd& q_start, Eigen::VectorXd* q_out,
                                              double limit_margin, int iterations) const {
  checkBase(base);
  checkArm(q_start);
  if (iterations < 1) fail("armInverseKinematicsFrom: iterations must be >= 1");
  const IkProblem p(*this, target, limit_margin, &base, static_cast<unsigned>(iterations));
  KDL::JntArray q0(p.n);
  for (unsigned i = 0; i < p.n; ++i) q0(i) = std::clamp(q_start[static_cast<Eigen::Index>(i)], p.lo(i), p.hi(i));
  return p.solve(q0, nullptr, q_out);
}

}  // namespace ehc_control
