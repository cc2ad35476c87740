#include "ehc_control/joint_limit_centring.h"

#include <algorithm>

namespace ehc_control {

namespace {
/// u of one margin: 0 at the influence border, 1 at (and beyond) the stop.
double proximity(double margin, double influence, double stop) {
  return std::clamp((influence - margin) / (influence - stop), 0.0, 1.0);
}
}  // namespace

double JointLimitCentring::potential(const Eigen::VectorXd& q, const Eigen::VectorXd& lower,
                                     const Eigen::VectorXd& upper) const {
  if (gain <= 0.0) return 0.0;
  double v = 0.0;
  for (int i = 0; i < q.size(); ++i) {
    const double ul = proximity(q[i] - lower[i], influence, stop), uu = proximity(upper[i] - q[i], influence, stop);
    v += (ul * ul * ul + uu * uu * uu) / 3.0;
  }
  return gain * (influence - stop) * v;
}

Eigen::VectorXd JointLimitCentring::gradient(const Eigen::VectorXd& q, const Eigen::VectorXd& lower,
                                             const Eigen::VectorXd& upper) const {
  Eigen::VectorXd g = Eigen::VectorXd::Zero(q.size());
  addGradient(q, lower, upper, g);
  return g;
}

void JointLimitCentring::addGradient(const Eigen::VectorXd& q, const Eigen::VectorXd& lower,
                                     const Eigen::VectorXd& upper, Eigen::Ref<Eigen::VectorXd> out) const {
  if (gain <= 0.0) return;
  for (int i = 0; i < q.size(); ++i) {
    const double ul = proximity(q[i] - lower[i], influence, stop), uu = proximity(upper[i] - q[i], influence, stop);
    // d/dq of (rho - s) u^3 / 3: du/dq = -1/(rho - s) for the lower side (margin q - lower),
    // +1/(rho - s) for the upper side; zero where u is clamped at 1 (beyond the stop) is
    // replaced by the value at the stop so that the push does not vanish there.
    out[i] += gain * (uu * uu - ul * ul);
  }
}

}  // namespace ehc_control
