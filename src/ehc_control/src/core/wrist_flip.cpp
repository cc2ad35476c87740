#include "ehc_control/wrist_flip.h"

#include "ehc_common/config_node.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <sstream>
#include <stdexcept>

using ehc_common::requireRange;

namespace ehc_control {

void WristFlipParams::validate() const {
  const char* owner = "WristFlipParams";
  requireRange(owner, "margin", margin, 0.0, 1.5);
  requireRange(owner, "speed", speed, 0.05, 20.0);
  requireRange(owner, "gain", gain, 0.1, 100.0);
  requireRange(owner, "tolerance", tolerance, 1e-4, 0.5);
}

std::string WristFlipParams::summary() const {
  std::ostringstream os;
  if (margin <= 0.0) return "wrist flip: off";
  os << "wrist flip: within " << margin << " rad of a limit, " << speed << " rad/s, gain " << gain << " 1/s, tolerance "
     << tolerance << " rad";
  return os.str();
}

std::vector<int> findFlipTriples(const WholeBodyModel& model) {
  const RobotConfig& rc = model.config();
  const int na = model.nArm();
  std::vector<int> out;
  std::mt19937 rng(17);
  for (int a = 0; a + 2 < na; ++a) {
    bool same = true;
    for (int trial = 0; trial < 5 && same; ++trial) {
      Eigen::VectorXd q(na);
      for (int i = 0; i < na; ++i)
        q[i] = std::uniform_real_distribution<double>(rc.arm_lower[i], rc.arm_upper[i])(rng);
      Eigen::VectorXd f = q;
      f[a] += M_PI;
      f[a + 1] = -f[a + 1];
      f[a + 2] += M_PI;
      const Eigen::Isometry3d p = model.linkPoseInBase(q, rc.tcp_frame), pf = model.linkPoseInBase(f, rc.tcp_frame);
      same = (p.matrix() - pf.matrix()).cwiseAbs().maxCoeff() < 1e-9;
    }
    if (same) out.push_back(a);
  }
  return out;
}

WristFlip::WristFlip(const WholeBodyModel& model, const WristFlipParams& params)
    : params_(params), lower_(model.config().arm_lower), upper_(model.config().arm_upper),
      names_(model.config().arm_joints) {
  params_.validate();
  if (params_.margin > 0.0) triples_ = findFlipTriples(model);
}

double WristFlip::margin(int joint, double value) const {
  return std::min(value - lower_[joint], upper_[joint] - value);
}

Eigen::Vector3d WristFlip::flipped(const Eigen::VectorXd& q, int a, double* min_margin) const {
  Eigen::Vector3d g;
  double worst = 1e9;
  for (int k = 0; k < 3; ++k) {
    const int j = a + k;
    if (k == 1) {
      g[k] = -q[j];
    } else {  // +pi or -pi: the one farther from the limits
      const double up = q[j] + M_PI, down = q[j] - M_PI;
      g[k] = margin(j, up) >= margin(j, down) ? up : down;
    }
    worst = std::min(worst, margin(j, g[k]));
  }
  if (min_margin) *min_margin = worst;
  return g;
}

bool WristFlip::update(const Eigen::VectorXd& q, const Eigen::VectorXd& last_arm_rates, bool may_run) {
  event_.clear();
  if (!may_run || triples_.empty()) {
    active_ = -1;
    return false;
  }
  if (active_ < 0) {
    for (const int a : triples_) {
      double current = 1e9;
      for (int k = 0; k < 3; ++k) current = std::min(current, margin(a + k, q[a + k]));
      for (const int j : {a, a + 2}) {
        const double to_lower = q[j] - lower_[j], to_upper = upper_[j] - q[j];
        const double m = std::min(to_lower, to_upper);
        if (m >= params_.margin) continue;
        // Rate towards the nearer limit; a joint clearly leaving the limit zone is left alone.
        const double towards = to_upper < to_lower ? last_arm_rates[j] : -last_arm_rates[j];
        if (towards < -0.05) continue;
        double after = 0.0;
        const Eigen::Vector3d g = flipped(q, a, &after);
        if (after <= current + params_.margin) continue;  // the other branch is no better
        active_ = a;
        goal_ = g;
        ++flips_;
        std::ostringstream os;
        os << "wrist flip " << names_[static_cast<std::size_t>(a)] << ".." << names_[static_cast<std::size_t>(a + 2)]
           << ": " << names_[static_cast<std::size_t>(j)] << " " << m << " rad from its limit, smallest margin "
           << current << " -> " << after << " rad";
        event_ = os.str();
        break;
      }
      if (active_ >= 0) break;
    }
    if (active_ < 0) return false;
  }
  const Eigen::Vector3d delta = goal_ - q.segment<3>(active_);
  const double largest = delta.cwiseAbs().maxCoeff();
  if (largest < params_.tolerance) {
    active_ = -1;
    return false;
  }
  rates_ = delta * std::min(params_.gain, params_.speed / largest);
  return true;
}

}  // namespace ehc_control
