// WholeBodyModel: Jacobian vs finite differences, FK vs the RM65-B modified-DH table,
// manipulability gradient vs finite differences, and bad inputs.

#include "ehc_control/whole_body_model.h"
#include "ehc_test/control_fixtures.h"
#include "ehc_test/test_seed.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>

using namespace ehc_control;
using ehc_control::test::randomArm;
using ehc_control::test::randomBase;
using ehc_control::test::realmanConfig;

namespace {

/// The two states of a central difference along one DOF: the base moves along its own x or y
/// axis or turns; an arm joint moves.
void perturb(const WholeBodyModel& m, const Eigen::Vector3d& base, const Eigen::VectorXd& q, int dof,
             double h, Eigen::Vector3d* bp, Eigen::Vector3d* bm, Eigen::VectorXd* qp, Eigen::VectorXd* qm) {
  *bp = *bm = base;
  *qp = *qm = q;
  const int nb = m.nBase();
  const bool holo = m.baseType() == BaseType::Holonomic;
  const double c = std::cos(base.z()), s = std::sin(base.z());
  if (dof < nb) {
    const bool is_wz = dof == nb - 1;
    const bool is_vy = holo && dof == 1;
    if (is_wz) {
      bp->z() += h;
      bm->z() -= h;
    } else if (is_vy) {  // move along the base y axis
      bp->head<2>() += h * Eigen::Vector2d(-s, c);
      bm->head<2>() -= h * Eigen::Vector2d(-s, c);
    } else {  // v_x: move along the base x axis
      bp->head<2>() += h * Eigen::Vector2d(c, s);
      bm->head<2>() -= h * Eigen::Vector2d(c, s);
    }
  } else {
    (*qp)[dof - nb] += h;
    (*qm)[dof - nb] -= h;
  }
}

/// World-frame twist [v; w] of `link` from central differences of FK along one DOF.
Eigen::Matrix<double, 6, 1> numericColumn(const WholeBodyModel& m, const Eigen::Vector3d& base,
                                          const Eigen::VectorXd& q, const std::string& link,
                                          int dof, double h) {
  Eigen::Vector3d bp, bm;
  Eigen::VectorXd qp, qm;
  perturb(m, base, q, dof, h, &bp, &bm, &qp, &qm);
  const Eigen::Isometry3d Tp = m.fk(bp, qp, link), Tm = m.fk(bm, qm, link);
  Eigen::Matrix<double, 6, 1> col;
  col.head<3>() = (Tp.translation() - Tm.translation()) / (2 * h);
  const Eigen::AngleAxisd aa(Eigen::Matrix3d(Tp.linear() * Tm.linear().transpose()));
  col.tail<3>() = aa.axis() * aa.angle() / (2 * h);
  return col;
}

/// The manipulability gradient against central differences of manipulability() at 100
/// random configurations.
void checkManipulabilityGradient(const WholeBodyModel& model, unsigned seed) {
  std::mt19937 rng(seed);
  Eigen::VectorXd g_into;
  for (int k = 0; k < 100; ++k) {
    const Eigen::VectorXd q = randomArm(model.config(), rng);
    double m = 0.0;
    const Eigen::VectorXd g = model.manipulabilityGradient(q, &m);
    EXPECT_NEAR(m, model.manipulability(q), 1e-12);
    model.manipulabilityGradientFromJacobian(model.armJacobian(q, model.config().tcp_frame), g_into);
    EXPECT_EQ(g_into, g);
    const double h = 1e-6;
    for (int i = 0; i < model.nArm(); ++i) {
      Eigen::VectorXd qp = q, qm = q;
      qp[i] += h;
      qm[i] -= h;
      const double num = (model.manipulability(qp) - model.manipulability(qm)) / (2 * h);
      EXPECT_NEAR(g[i], num, 1e-6 + 1e-5 * std::abs(num)) << "sample " << k << " joint " << i;
    }
  }
}

/// Modified DH (Craig): T = RotX(alpha_{i-1}) TransX(a_{i-1}) RotZ(theta_i) TransZ(d_i).
Eigen::Isometry3d rm65ModifiedDh(const Eigen::VectorXd& q) {
  const double a[6] = {0, 0, 0.256, 0, 0, 0};
  const double alpha_deg[6] = {0, 90, 0, 90, -90, 90};
  const double d[6] = {0.2405, 0, 0, 0.210, 0, 0.144};
  const double offset_deg[6] = {0, 90, 90, 0, 0, 0};
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  for (int i = 0; i < 6; ++i) {
    Eigen::Isometry3d Ti = Eigen::Isometry3d::Identity();
    Ti.rotate(Eigen::AngleAxisd(alpha_deg[i] * M_PI / 180.0, Eigen::Vector3d::UnitX()));
    Ti.translate(Eigen::Vector3d(a[i], 0, 0));
    Ti.rotate(Eigen::AngleAxisd(q[i] + offset_deg[i] * M_PI / 180.0, Eigen::Vector3d::UnitZ()));
    Ti.translate(Eigen::Vector3d(0, 0, d[i]));
    T = T * Ti;
  }
  return T;
}

std::string readText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace

class JacobianVsFiniteDifferences : public ::testing::TestWithParam<BaseType> {};

TEST_P(JacobianVsFiniteDifferences, HundredRandomConfigurationsSeveralLinks) {
  const WholeBodyModel model(realmanConfig(GetParam()));
  std::mt19937 rng(42);
  double worst = 0.0;
  for (int k = 0; k < 100; ++k) {
    const Eigen::VectorXd q = randomArm(model.config(), rng);
    const Eigen::Vector3d base = randomBase(rng);
    for (const std::string link : {"ee_link", "camera_color_optical_frame", "link3", "link6"}) {
      const Matrix6Xd J = model.jacobian(base, q, link);
      ASSERT_EQ(J.rows(), 6);
      ASSERT_EQ(J.cols(), model.nDof());
      for (int dof = 0; dof < model.nDof(); ++dof) {
        const auto num = numericColumn(model, base, q, link, dof, 1e-6);
        const double err = (J.col(dof) - num).cwiseAbs().maxCoeff();
        worst = std::max(worst, err);
        ASSERT_LE(err, 1e-6) << "link " << link << " dof " << model.dofNames()[dof]
                             << " sample " << k << "\nanalytic " << J.col(dof).transpose()
                             << "\nnumeric  " << num.transpose();
      }
    }
  }
  RecordProperty("worst_abs_error", std::to_string(worst));
}

INSTANTIATE_TEST_SUITE_P(BothBaseTypes, JacobianVsFiniteDifferences,
                         ::testing::Values(BaseType::Holonomic, BaseType::Differential),
                         [](const auto& info) { return toString(info.param); });

namespace {

/// A 4-DOF arm with what the RealMan arm lacks: a prismatic arm joint, a continuous joint, a
/// non-unit axis, tilted joint origins and a movable joint that is no arm joint (a finger,
/// held at 0).
const char* kToyUrdf = R"(<robot name="toy">
  <link name="base_link"/><link name="arm_base_link"/><link name="l1"/><link name="l2"/>
  <link name="l3"/><link name="l4"/><link name="ee_link"/><link name="camera_color_optical_frame"/>
  <link name="finger"/>
  <joint name="mount" type="fixed"><parent link="base_link"/><child link="arm_base_link"/>
    <origin xyz="0.1 0.05 0.5" rpy="0 0 0.3"/></joint>
  <joint name="j1" type="revolute"><parent link="arm_base_link"/><child link="l1"/>
    <origin xyz="0 0.02 0.2" rpy="0.1 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" velocity="2" effort="1"/></joint>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/>
    <origin xyz="0.05 0 0.1" rpy="1.2 0.3 0"/><axis xyz="0 2 1"/>
    <limit lower="-2" upper="2" velocity="2" effort="1"/></joint>
  <joint name="j3" type="prismatic"><parent link="l2"/><child link="l3"/>
    <origin xyz="0.3 0 0.01" rpy="0 0.2 0"/><axis xyz="1 0 0"/>
    <limit lower="0" upper="0.3" velocity="0.5" effort="1"/></joint>
  <joint name="j4" type="continuous"><parent link="l3"/><child link="l4"/>
    <origin xyz="0 0.1 0" rpy="0 0 0.5"/><axis xyz="0 -1 0"/></joint>
  <joint name="tcp_joint" type="fixed"><parent link="l4"/><child link="ee_link"/>
    <origin xyz="0 0 0.12" rpy="0 0.4 0"/></joint>
  <joint name="camera_mount_joint" type="fixed"><parent link="l4"/>
    <child link="camera_color_optical_frame"/><origin xyz="0.07 0 0.03" rpy="0 -1.5 0"/></joint>
  <joint name="finger_joint" type="prismatic"><parent link="l4"/><child link="finger"/>
    <origin xyz="0 0.02 0.1"/><axis xyz="0 1 0"/>
    <limit lower="0" upper="0.04" velocity="0.1" effort="1"/></joint>
</robot>)";

RobotConfig toyConfig(BaseType type) {
  RobotConfig c;
  c.urdf_path = "toy.urdf";  // not read: the XML is passed to the model
  c.base_type = type;
  c.arm_joints = {"j1", "j2", "j3", "j4"};
  c.arm_lower = Eigen::Vector4d(-3, -2, 0, -6);
  c.arm_upper = Eigen::Vector4d(3, 2, 0.3, 6);
  c.arm_velocity = Eigen::Vector4d(2, 2, 0.5, 2);
  c.arm_ready = Eigen::Vector4d(0, 0.5, 0.1, 0);
  return c;
}

/// The one-pass kinematics (updateKinematics + the KinematicState Jacobians) against the
/// per-link KDL chains (fk, jacobian, armJacobian) for every link, and the Jacobian of a point
/// fixed to each link against finite differences of its FK position; returns the worst error.
double checkOnePassKinematics(const WholeBodyModel& model, int samples, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  KinematicState state;
  Matrix6Xd J, Ja, Jp;
  double worst = 0.0;
  for (int k = 0; k < samples; ++k) {
    const Eigen::VectorXd q = randomArm(model.config(), rng);
    const Eigen::Vector3d base = randomBase(rng);
    model.updateKinematics(base, q, &state);
    for (const std::string& link : model.linkNames()) {
      const int i = model.linkIndex(link);
      SCOPED_TRACE("link " + link + " sample " + std::to_string(k));
      const Eigen::Isometry3d T = model.fk(base, q, link);
      const double pose_err = (state.linkPose(i).matrix() - T.matrix()).cwiseAbs().maxCoeff();
      EXPECT_LE(pose_err, 1e-12);
      EXPECT_LE((state.linkPoseInBase(i).matrix() - model.linkPoseInBase(q, link).matrix()).cwiseAbs().maxCoeff(), 1e-12);
      model.jacobian(state, i, &J, &Ja);
      const Matrix6Xd J_kdl = model.jacobian(base, q, link);
      const double jac_err = (J - J_kdl).cwiseAbs().maxCoeff();
      EXPECT_LE(jac_err, 1e-12) << "\none pass\n" << J << "\nKDL\n" << J_kdl;
      EXPECT_LE((Ja - model.armJacobian(q, link)).cwiseAbs().maxCoeff(), 1e-12);
      // A point fixed to the link: linear rows against central differences of its position,
      // angular rows are the link's.
      const Eigen::Vector3d offset(u(rng), u(rng), u(rng)), p = T * offset;
      model.pointJacobian(state, i, p, &Jp);
      EXPECT_LE((Jp.bottomRows<3>() - J_kdl.bottomRows<3>()).cwiseAbs().maxCoeff(), 1e-12);
      double point_err = 0.0;
      for (int dof = 0; dof < model.nDof(); ++dof) {
        const double h = 1e-6;
        Eigen::Vector3d bp, bm;
        Eigen::VectorXd qp, qm;
        perturb(model, base, q, dof, h, &bp, &bm, &qp, &qm);
        const Eigen::Vector3d num =
            (model.fk(bp, qp, link) * offset - model.fk(bm, qm, link) * offset) / (2 * h);
        point_err = std::max(point_err, (Jp.block<3, 1>(0, dof) - num).cwiseAbs().maxCoeff());
      }
      EXPECT_LE(point_err, 1e-6);
      worst = std::max({worst, pose_err, jac_err});
    }
  }
  return worst;
}

}  // namespace

class OnePassKinematics : public ::testing::TestWithParam<BaseType> {};

TEST_P(OnePassKinematics, RealmanEveryLinkMatchesKdlAndFiniteDifferences) {
  const WholeBodyModel model(realmanConfig(GetParam()));
  std::ostringstream worst;
  worst << checkOnePassKinematics(model, 100, 7);
  RecordProperty("worst_abs_error_vs_kdl", worst.str());
}

TEST_P(OnePassKinematics, PrismaticContinuousAndHeldJointsMatchKdlAndFiniteDifferences) {
  const WholeBodyModel model(toyConfig(GetParam()), kToyUrdf);
  ASSERT_EQ(model.linkNames().size(), 9u);
  std::ostringstream worst;
  worst << checkOnePassKinematics(model, 100, 8);
  RecordProperty("worst_abs_error_vs_kdl", worst.str());
}

INSTANTIATE_TEST_SUITE_P(BothBaseTypes, OnePassKinematics,
                         ::testing::Values(BaseType::Holonomic, BaseType::Differential),
                         [](const auto& info) { return toString(info.param); });

TEST(WholeBodyModel, LinkIndexResolvesEveryLinkAndRejectsUnknownOnes) {
  const WholeBodyModel model(realmanConfig());
  std::vector<bool> seen(model.linkNames().size(), false);
  for (const std::string& link : model.linkNames()) {
    const int i = model.linkIndex(link);
    ASSERT_GE(i, 0);
    ASSERT_LT(i, static_cast<int>(seen.size()));
    EXPECT_FALSE(seen[static_cast<std::size_t>(i)]) << link;
    seen[static_cast<std::size_t>(i)] = true;
  }
  try {
    model.linkIndex("no_such_link");
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("[WholeBodyModel] unknown link 'no_such_link'"), std::string::npos);
  }
  KinematicState state;
  Eigen::VectorXd q = model.config().arm_ready;
  q[1] = std::nan("");
  EXPECT_THROW(model.updateKinematics(Eigen::Vector3d::Zero(), q, &state), std::invalid_argument);
}

TEST(WholeBodyModel, BaseColumnsMatchTheBaseType) {
  const WholeBodyModel holo(realmanConfig(BaseType::Holonomic));
  const WholeBodyModel diff(realmanConfig(BaseType::Differential));
  EXPECT_EQ(holo.nDof(), 9);
  EXPECT_EQ(diff.nDof(), 8);
  EXPECT_EQ(holo.dofNames()[1], "base_vy");
  EXPECT_EQ(diff.dofNames()[1], "base_wz");
  std::mt19937 rng(1);
  const Eigen::VectorXd q = randomArm(holo.config(), rng);
  const Eigen::Vector3d base(1.0, -2.0, 0.7);
  const Matrix6Xd Jh = holo.jacobian(base, q, "ee_link");
  const Matrix6Xd Jd = diff.jacobian(base, q, "ee_link");
  // Differential = holonomic without the v_y column.
  EXPECT_TRUE(Jd.col(0).isApprox(Jh.col(0)));
  EXPECT_TRUE(Jd.col(1).isApprox(Jh.col(2)));
  EXPECT_TRUE(Jd.rightCols(6).isApprox(Jh.rightCols(6)));
  // v_x of the base moves every point along the base heading, no rotation.
  EXPECT_NEAR(Jh(0, 0), std::cos(0.7), 1e-12);
  EXPECT_NEAR(Jh(1, 0), std::sin(0.7), 1e-12);
  EXPECT_NEAR(Jh.col(0).tail<3>().norm(), 0.0, 1e-12);
}

TEST(WholeBodyModel, ForwardKinematicsMatchesModifiedDhTable) {
  const WholeBodyModel model(realmanConfig());
  std::mt19937 rng(7);
  for (int k = 0; k < 200; ++k) {
    const Eigen::VectorXd q = randomArm(model.config(), rng, 0.0);
    const Eigen::Vector3d base = randomBase(rng);
    const Eigen::Isometry3d Twa = model.fk(base, q, "arm_base_link");
    const Eigen::Isometry3d Tw6 = model.fk(base, q, "link6");
    const Eigen::Isometry3d dh = rm65ModifiedDh(q);
    const Eigen::Isometry3d rel = Twa.inverse() * Tw6;
    EXPECT_LE((rel.translation() - dh.translation()).norm(), 1e-6) << "sample " << k;
    const Eigen::AngleAxisd dR(Eigen::Matrix3d(rel.linear().transpose() * dh.linear()));
    EXPECT_LE(std::abs(dR.angle()), 1e-6) << "sample " << k;
    // The arm base sits 0.10 m forward and 0.60 m up on the base (documented mount).
    const Eigen::Vector3d mount = WholeBodyModel::baseTransform(base) * Eigen::Vector3d(0.10, 0, 0.60);
    EXPECT_LE((Twa.translation() - mount).norm(), 1e-9);
    // TCP = 0.12 m along the flange z axis.
    const Eigen::Isometry3d Twe = model.fk(base, q, "ee_link");
    EXPECT_LE((Twe.translation() - Tw6 * Eigen::Vector3d(0, 0, 0.12)).norm(), 1e-9);
  }
}

TEST(WholeBodyModel, CameraLooksAlongTheApproachAxis) {
  const WholeBodyModel model(realmanConfig());
  const Eigen::VectorXd q = model.config().arm_ready;
  const Eigen::Isometry3d Tc = model.fk(Eigen::Vector3d::Zero(), q, "camera_color_optical_frame");
  const Eigen::Isometry3d Te = model.fk(Eigen::Vector3d::Zero(), q, "ee_link");
  EXPECT_NEAR(Tc.linear().col(2).dot(Te.linear().col(2)), 1.0, 1e-9);
  // 0.07 m off the approach axis.
  const Eigen::Vector3d d = Te.inverse() * Tc.translation();
  EXPECT_NEAR(std::hypot(d.x(), d.y()), 0.07, 1e-9);
}

// The hand camera's image is upright in the ready pose, on every shipped robot, with
// robot.yaml's calibration and with the URDF's own mount. Optical frame: z forward, x right,
// y down. Upright: in the ready pose (base at the origin, facing +x) the image's down (y) points
// to the floor and its right (x) to the robot's right (-y).
TEST(WholeBodyModel, CameraImageIsUprightInTheReadyPose) {
  for (const std::string& robot : robotNames()) {
    const RobotConfig calibrated = loadRobotConfig(resolveRobotFile(robot));
    RobotConfig uncalibrated = calibrated;
    uncalibrated.calibration.clear();
    for (const RobotConfig& rc : {calibrated, uncalibrated}) {
      SCOPED_TRACE(robot + (rc.calibration.empty() ? " (URDF mount)" : " (robot.yaml mount)"));
      const WholeBodyModel model(rc);
      const Eigen::Isometry3d Tc =
          model.fk(Eigen::Vector3d::Zero(), rc.arm_ready, "camera_color_optical_frame");
      EXPECT_LT(Tc.linear().col(1).z(), -0.9) << "image down must point to the floor";
      EXPECT_LT(Tc.linear().col(0).y(), -0.99) << "image right must be the robot's right";
      EXPECT_GT(Tc.linear().col(2).x(), 0.9) << "looking ahead";
      // The camera sits above the gripper (on the flange's +x side, which points up here).
      const Eigen::Isometry3d Te = model.fk(Eigen::Vector3d::Zero(), rc.arm_ready, "ee_link");
      EXPECT_GT(Tc.translation().z(), Te.translation().z());
    }
  }
}

// robot_state_publisher on the real robot publishes calibratedUrdfXml() (run_realman.sh): the
// bare URDF with robot.yaml's calibration gives the same frames as the calibrated model.
TEST(WholeBodyModel, CalibratedUrdfCarriesTheCalibration) {
  RobotConfig rc = realmanConfig();
  for (auto& c : rc.calibration) {  // a calibration that differs from the URDF's values
    c.xyz += Eigen::Vector3d(0.011, -0.007, 0.005);
    c.rpy += Eigen::Vector3d(0.03, -0.02, 0.05);
  }
  const WholeBodyModel calibrated(rc);
  RobotConfig bare = rc;
  bare.calibration.clear();
  const WholeBodyModel from_xml(bare, calibrated.calibratedUrdfXml());
  const WholeBodyModel plain(bare);
  for (const char* link : {"ee_link", "camera_color_optical_frame"}) {
    const Eigen::Isometry3d a = calibrated.linkPoseInBase(rc.arm_ready, link);
    const Eigen::Isometry3d b = from_xml.linkPoseInBase(rc.arm_ready, link);
    EXPECT_LT((a.translation() - b.translation()).norm(), 1e-5) << link;
    EXPECT_LT(Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle(), 1e-5) << link;
    EXPECT_GT((a.translation() - plain.linkPoseInBase(rc.arm_ready, link).translation()).norm(), 1e-3)
        << "the calibration must differ from the URDF for this test to mean anything";
  }
}

TEST(WholeBodyModel, ManipulabilityGradientMatchesFiniteDifferences) {
  checkManipulabilityGradient(WholeBodyModel(realmanConfig()), 3);
}

TEST(WholeBodyModel, ManipulabilityGradientOfAFourJointArmMatchesFiniteDifferences) {
  // nArm < 6: m = sqrt(det(J^T J)).
  checkManipulabilityGradient(WholeBodyModel(toyConfig(BaseType::Differential), kToyUrdf), 5);
}

TEST(WholeBodyModel, ManipulabilityVanishesAtTheElbowSingularity) {
  const WholeBodyModel model(realmanConfig());
  Eigen::VectorXd q = model.config().arm_ready;
  q[2] = 0.0;  // RM65-B: singular at q3 = 0 (arm stretched)
  EXPECT_LT(model.manipulability(q), 1e-9);
  EXPECT_GT(model.manipulability(model.config().arm_ready), 1e-3);
  EXPECT_TRUE(model.manipulabilityGradient(q).allFinite());
}

TEST(WholeBodyModel, CalibrationOverridesMoveTheTcp) {
  RobotConfig c = realmanConfig();
  for (auto& o : c.calibration)
    if (o.joint == "tcp_joint") o.xyz = Eigen::Vector3d(0, 0, 0.20);
  const WholeBodyModel model(c);
  const Eigen::VectorXd q = c.arm_ready;
  const Eigen::Isometry3d T6 = model.linkPoseInBase(q, "link6");
  const Eigen::Isometry3d Te = model.linkPoseInBase(q, "ee_link");
  EXPECT_NEAR((Te.translation() - T6 * Eigen::Vector3d(0, 0, 0.20)).norm(), 0.0, 1e-9);
}

// ------------------------------------------------------------------ bad inputs

TEST(WholeBodyModelErrors, WrongJointCount) {
  const WholeBodyModel model(realmanConfig());
  try {
    model.fk(Eigen::Vector3d::Zero(), Eigen::VectorXd::Zero(5), "ee_link");
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("[WholeBodyModel] expected 6 arm joint positions, got 5"),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW(model.jacobian(Eigen::Vector3d::Zero(), Eigen::VectorXd::Zero(7), "ee_link"),
               std::invalid_argument);
  EXPECT_THROW(model.manipulabilityGradient(Eigen::VectorXd::Zero(2)), std::invalid_argument);
}

TEST(WholeBodyModelErrors, NaNInputs) {
  const WholeBodyModel model(realmanConfig());
  Eigen::VectorXd q = model.config().arm_ready;
  q[3] = std::nan("");
  EXPECT_THROW(model.fk(Eigen::Vector3d::Zero(), q, "ee_link"), std::invalid_argument);
  EXPECT_THROW(model.manipulability(q), std::invalid_argument);
  const Eigen::Vector3d bad_base(0, std::numeric_limits<double>::infinity(), 0);
  EXPECT_THROW(model.jacobian(bad_base, model.config().arm_ready, "ee_link"), std::invalid_argument);
}

TEST(WholeBodyModelErrors, UnknownLink) {
  const WholeBodyModel model(realmanConfig());
  try {
    model.fk(Eigen::Vector3d::Zero(), model.config().arm_ready, "no_such_link");
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("[WholeBodyModel] unknown link 'no_such_link'"),
              std::string::npos);
  }
}

TEST(WholeBodyModelErrors, UnreadableOrBrokenUrdf) {
  RobotConfig c = realmanConfig();
  c.urdf_path = "/nonexistent/robot.urdf";
  try {
    WholeBodyModel m(c);
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    const std::string w = e.what();
    EXPECT_NE(w.find("[WholeBodyModel] " + c.source_file + ": field 'robot.urdf' names a file that cannot be read "
                     "(URDF /nonexistent/robot.urdf)"),
              std::string::npos) << w;
  }
  EXPECT_THROW(WholeBodyModel(realmanConfig(), "<robot name='x'><link name="), std::invalid_argument);
}

TEST(WholeBodyModelErrors, ConfigThatDoesNotMatchTheUrdfNamesTheFileAndTheField) {
  // Every robot-folder mismatch is a start-up error naming robot.yaml and the field (the
  // simulators and the sequencer check the robot through this model too).
  const RobotConfig good = realmanConfig();
  const std::string xml = readText(good.urdf_path);
  auto expectError = [&](const RobotConfig& c, const std::string& field, const std::string& what) {
    try {
      WholeBodyModel m(c, xml);
      FAIL() << field << ": no exception";
    } catch (const std::invalid_argument& e) {
      const std::string w = e.what();
      EXPECT_NE(w.find(good.source_file + ": field '" + field + "' "), std::string::npos) << w;
      EXPECT_NE(w.find(what), std::string::npos) << w;
    }
  };
  {
    RobotConfig c = good;
    c.arm_joints[2] = "elbow";  // not in the URDF
    expectError(c, "robot.arm.joints", "names joint 'elbow' which is not in the URDF");
  }
  {
    RobotConfig c = good;
    std::swap(c.arm_joints[0], c.arm_joints[1]);  // wrong order (each with its own limits)
    std::swap(c.arm_lower[0], c.arm_lower[1]);
    std::swap(c.arm_upper[0], c.arm_upper[1]);
    std::swap(c.arm_velocity[0], c.arm_velocity[1]);
    std::swap(c.arm_ready[0], c.arm_ready[1]);
    expectError(c, "robot.arm.joints", "must be the movable joints");
  }
  {
    RobotConfig c = good;
    c.arm_upper[1] = 3.0;  // wider than the URDF's 130 deg
    expectError(c, "robot.arm.lower/upper", "of joint 'joint2' are wider than the URDF's limits");
  }
  {
    RobotConfig c = good;
    c.calibration.push_back({"tcp", "joint3", Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()});
    expectError(c, "robot.calibration.tcp.joint", "must be a fixed joint");
  }
  {
    RobotConfig c = good;
    c.calibration.push_back({"camera", "no_such_mount", Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()});
    expectError(c, "robot.calibration.camera.joint", "names joint 'no_such_mount' which is not in the URDF");
  }
  {
    RobotConfig c = good;
    c.tcp_frame = "gripper_tip";  // no such link
    expectError(c, "robot.frames.tcp", "names link 'gripper_tip' which is not in the URDF");
  }
  {
    RobotConfig c = good;
    c.camera_frame = "camera_typo";
    expectError(c, "robot.frames.camera_optical", "names link 'camera_typo' which is not in the URDF");
  }
  {
    RobotConfig c = good;
    c.base_frame = "footprint";
    expectError(c, "robot.frames.base", "the URDF's root link is 'base_link'");
  }
}

TEST(WholeBodyModel, InverseKinematicsFindsReachablePosesAndRejectsUnreachableOnes) {
  const WholeBodyModel model(realmanConfig());
  std::mt19937 rng(11);
  int found = 0;
  for (int k = 0; k < 20; ++k) {
    // A pose produced by FK is reachable by construction.
    const Eigen::VectorXd q = randomArm(model.config(), rng, 0.2);
    const Eigen::Vector3d base = randomBase(rng);
    const Eigen::Isometry3d T = model.fk(base, q, "ee_link");
    Eigen::Vector3d b;
    Eigen::VectorXd qs;
    if (model.inverseKinematics(T, 1, 20, &b, &qs)) {
      ++found;
      const Eigen::Isometry3d S = model.fk(b, qs, "ee_link");
      EXPECT_LT((S.translation() - T.translation()).norm(), 1e-3);
      EXPECT_TRUE(((qs - model.config().arm_lower).array() >= -1e-9).all());
      EXPECT_TRUE(((model.config().arm_upper - qs).array() >= -1e-9).all());
    }
  }
  EXPECT_GE(found, 18);
  // A TCP 3 m above the floor is out of reach for any base pose.
  Eigen::Isometry3d high = Eigen::Isometry3d::Identity();
  high.translation() << 1.0, 0.0, 3.0;
  EXPECT_FALSE(model.inverseKinematics(high, 1, 20));
}

TEST(WholeBodyModel, ArmInverseKinematicsHoldsTheBase) {
  // From a start near a pose FK produced, the arm alone reaches it with the base held where it
  // is; a target beyond the arm's reach from that base is not reached (the whole body would).
  const WholeBodyModel model(realmanConfig());
  const unsigned seed = ehc_test::testSeed("arm IK with the base held");
  std::mt19937 rng(seed);
  int found = 0;
  for (int k = 0; k < 20; ++k) {
    const Eigen::VectorXd q = randomArm(model.config(), rng, 0.3);
    const Eigen::Vector3d base = randomBase(rng);
    const Eigen::Isometry3d T = model.fk(base, q, "ee_link");
    Eigen::VectorXd start = q;
    for (int i = 0; i < start.size(); ++i) start[i] += std::uniform_real_distribution<double>(-0.2, 0.2)(rng);
    Eigen::VectorXd qs;
    if (model.armInverseKinematicsFrom(T, base, start, &qs, 0.05)) {
      ++found;
      const Eigen::Isometry3d S = model.fk(base, qs, "ee_link");
      EXPECT_LT((S.translation() - T.translation()).norm(), 1e-3);
      EXPECT_TRUE(((qs - model.config().arm_lower).array() >= 0.05 - 1e-9).all());
      EXPECT_TRUE(((model.config().arm_upper - qs).array() >= 0.05 - 1e-9).all());
    }
  }
  EXPECT_GE(found, 16);
  const Eigen::Vector3d base(0.0, 0.0, 0.0);
  Eigen::Isometry3d far = model.fk(base, model.config().arm_ready, "ee_link");
  far.translation().x() += 2.0;  // the ready TCP 2 m ahead
  Eigen::VectorXd qs;
  EXPECT_FALSE(model.armInverseKinematicsFrom(far, base, model.config().arm_ready, &qs));
  EXPECT_TRUE(model.inverseKinematics(far, 1, 20));
  EXPECT_NE(ehc_test::errorOf([&] { model.armInverseKinematicsFrom(far, base, model.config().arm_ready, &qs, 0.0, 0); })
                .find("iterations"),
            std::string::npos);
}
