#include "ehc_bringup/grasp_trace.h"

#include "ehc_control/joint_state.h"

#include <cmath>
#include <iomanip>
#include <limits>
#include <stdexcept>

namespace ehc_bringup {

GraspTraceWriter::GraspTraceWriter(const std::string& path) : file_(path) {
  if (!file_) throw std::runtime_error("[GraspTraceWriter] cannot write the trace file " + path);
  file_ << kHeader << "\n";
}

void GraspTraceWriter::write(const GraspTraceRow& r) {
  file_ << std::fixed << std::setprecision(3) << r.t << "," << r.object << "," << toString(r.phase) << ","
        << r.controller_phase << "," << std::setprecision(5) << r.error_norm << "," << r.position_error << ","
        << r.sig_omega << "," << r.base_speed << "," << r.base_turn << "," << r.arm_speed << ","
        << (r.target_in_fov ? 1 : 0) << "," << r.obstacle_rows << "," << r.qp_status << "\n";
}

bool writeGraspSummaryFile(const std::string& path, const std::string& json) {
  std::ofstream f(path);
  f << json << "\n";
  return static_cast<bool>(f);
}

double jointStateArmSpeed(const std::vector<std::string>& arm_joints, const std::vector<std::string>& names,
                          const std::vector<double>& velocities) {
  Eigen::VectorXd rates;
  if (!ehc_control::armPositionsFromJointState(arm_joints, names, velocities, &rates).empty())
    return std::numeric_limits<double>::quiet_NaN();
  // A plain sum in arm_joints order (the simulator's order): the bits the trace always had
  // (Eigen's vectorised norm may round differently).
  double sum = 0.0;
  for (Eigen::Index i = 0; i < rates.size(); ++i) sum += rates[i] * rates[i];
  return std::sqrt(sum);
}

}  // namespace ehc_bringup
