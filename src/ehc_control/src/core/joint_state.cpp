#include "ehc_control/joint_state.h"

namespace ehc_control {

std::string armPositionsFromJointState(const std::vector<std::string>& arm_joints,
                                       const std::vector<std::string>& names,
                                       const std::vector<double>& positions, Eigen::VectorXd* q) {
  if (names.size() != positions.size())
    return "joint state has " + std::to_string(names.size()) + " names but " +
           std::to_string(positions.size()) + " positions";
  Eigen::VectorXd arm(static_cast<Eigen::Index>(arm_joints.size()));
  for (std::size_t i = 0; i < arm_joints.size(); ++i) {
    const std::string& want = arm_joints[i];
    std::size_t k = 0;
    while (k < names.size() && names[k] != want) ++k;
    if (k == names.size()) return "joint state lacks arm joint '" + want + "'";
    arm[static_cast<Eigen::Index>(i)] = positions[k];
  }
  if (!arm.allFinite()) return "joint state contains NaN or Inf";
  *q = arm;
  return "";
}

}  // namespace ehc_control
