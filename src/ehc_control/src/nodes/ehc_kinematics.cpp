// ehc_kinematics: scripting CLI over WholeBodyModel (ROS-free, runs without a master).
//   rosrun ehc_control ehc_kinematics --robot robot.yaml --q j1,...,jn [--base x,y,yaw]
//                                     [--link NAME] [--summary]
//   rosrun ehc_control ehc_kinematics --robot robot.yaml --urdf
//   rosrun ehc_control ehc_kinematics --robot robot.yaml --check [--view-region x0,x1,y0,y1,z0,z1]
// Prints one JSON object {"joint_names", "base_type", "T", "J", "manipulability"} (T and J of
// --link, default the TCP, world frame). --q ready uses the ready pose of robot.yaml.
// --summary prints a human-readable kinematic summary instead. --urdf prints the URDF with
// robot.yaml's calibration applied (robot_description for robot_state_publisher, run_realman.sh).
// --check runs ehc_control::checkRobot: one "ok <check>: ..." line per check that passes and one
// "PROBLEM <check>: ..." line per problem; exit code 0 when there is none, 1 otherwise.
// Errors: stderr, exit code 2.

#include "ehc_common/command_line.h"
#include "ehc_common/json.h"
#include "ehc_control/robot_check.h"
#include "ehc_control/whole_body_model.h"

#include <cstdio>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

namespace {

const char* kUsage =
    "usage: ehc_kinematics --robot <robot.yaml> --q <j1,...,jn | ready> [--base x,y,yaw]\n"
    "                      [--link NAME] [--summary]\n"
    "       ehc_kinematics --robot <robot.yaml> --urdf   (the calibrated URDF)\n"
    "       ehc_kinematics --robot <robot.yaml> --check [--view-region x0,x1,y0,y1,z0,z1]\n"
    "                      (what will go wrong: exit 0 when nothing, 1 with one line per problem)\n";

struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

ehc_common::Json matrixJson(const Eigen::MatrixXd& m) {
  ehc_common::Json rows = ehc_common::Json::array();
  for (int r = 0; r < m.rows(); ++r) {
    ehc_common::Json row = ehc_common::Json::array();
    for (int c = 0; c < m.cols(); ++c) row.push_back(ehc_common::jsonNumber(m(r, c)));
    rows.push_back(row);
  }
  return rows;
}

void printSummary(const ehc_control::WholeBodyModel& model, const Eigen::Vector3d& base,
                  const Eigen::VectorXd& q) {
  const auto& c = model.config();
  std::cout << c.summary();
  std::cout << "  DOF: " << model.nDof() << " (" << model.nBase() << " base + " << model.nArm()
            << " arm):";
  for (const auto& n : model.dofNames()) std::cout << " " << n;
  std::cout << "\n  links: " << model.linkNames().size() << "\n";
  std::cout << std::fixed << std::setprecision(4);
  for (const std::string& f : {c.arm_base_frame, c.tcp_frame, c.camera_frame}) {
    const Eigen::Isometry3d T = model.fk(base, q, f);
    std::cout << "  " << std::setw(28) << std::left << f << " at q: position ["
              << T.translation().transpose() << "] m, z axis [" << T.linear().col(2).transpose()
              << "]\n";
  }
  const Eigen::Vector3d reach =
      model.linkPoseInBase(q, c.tcp_frame).translation() -
      model.linkPoseInBase(q, c.arm_base_frame).translation();
  std::cout << "  TCP distance from the arm base: " << reach.norm() << " m\n";
  std::cout << "  manipulability at q: " << model.manipulability(q) << "\n";
}

/// --check: every check of the robot folder, one line each; exit code 1 on any problem.
int runCheck(const ehc_common::CommandLine& cli, const std::string& robot) {
  ehc_control::RobotCheckParams params;
  if (cli.has("view-region")) {
    const std::vector<double> v = cli.reals("view-region", {});
    if (v.size() != 6) throw UsageError("--view-region needs 6 values x0,x1,y0,y1,z0,z1 (m), got " + std::to_string(v.size()));
    params.view_min = Eigen::Vector3d(v[0], v[2], v[4]);
    params.view_max = Eigen::Vector3d(v[1], v[3], v[5]);
    if ((params.view_min.array() > params.view_max.array()).any()) throw UsageError("--view-region: each min must be <= its max");
  }
  const std::vector<ehc_control::RobotCheckLine> lines = ehc_control::checkRobot(robot, params);
  for (const auto& l : lines) std::cout << ehc_control::toString(l) << "\n";
  std::cout << std::flush;
  return ehc_control::allOk(lines) ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const ehc_common::CommandLine cli(argc, argv, {"robot", "q", "base", "link", "view-region"},
                                       {"summary", "urdf", "check", "help"});
    if (cli.has("help")) {
      std::cout << kUsage;
      return 0;
    }
    const std::string robot = ehc_control::resolveRobotFile(cli.text("robot"));  // a robot name or a robot.yaml
    if (cli.has("check")) return runCheck(cli, robot);
    if (cli.has("urdf")) {
      std::cout << ehc_control::WholeBodyModel(ehc_control::loadRobotConfig(robot)).calibratedUrdfXml();
      return 0;
    }
    const bool summary = cli.has("summary");
    if (!summary) cli.text("q");  // "--q is required"
    const std::string q_arg = cli.text("q", "");
    std::string link = cli.text("link", "");

    const ehc_control::RobotConfig cfg = ehc_control::loadRobotConfig(robot);
    const ehc_control::WholeBodyModel model(cfg);
    if (link.empty()) link = cfg.tcp_frame;

    Eigen::VectorXd q = cfg.arm_ready;
    if (!q_arg.empty() && q_arg != "ready") {
      const std::vector<double> v = ehc_common::CommandLine::parseReals("--q", q_arg);
      if (static_cast<int>(v.size()) != model.nArm())
        throw UsageError("--q needs " + std::to_string(model.nArm()) + " values, got " +
                         std::to_string(v.size()));
      q = Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<int>(v.size()));
    }
    const Eigen::Vector3d base = cli.vector3("base", Eigen::Vector3d::Zero());  // x, y, yaw

    if (summary) {
      printSummary(model, base, q);
      return 0;
    }
    Eigen::Isometry3d T;
    const ehc_control::Matrix6Xd J = model.jacobian(base, q, link, &T);
    ehc_common::Json out;
    out["joint_names"] = cfg.arm_joints;
    out["base_type"] = ehc_control::toString(cfg.base_type);
    out["link"] = link;
    out["T"] = matrixJson(T.matrix());
    out["J"] = matrixJson(J);
    out["manipulability"] = ehc_common::jsonNumber(model.manipulability(q));
    std::cout << ehc_common::jsonLine(out) << std::endl;
    return 0;
  } catch (const UsageError& e) {
    std::cerr << "ehc_kinematics: " << e.what() << "\n" << kUsage;
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "ehc_kinematics: " << e.what() << "\n";
    return 2;
  }
}
