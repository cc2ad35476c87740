#pragma once
// WristFlip: the joint-limit escape of the EHC QP. ROS-free.
//
// The trap it removes (Exp-1 traces, RealMan RM65-B): while the base still drives towards a
// far target, the orientation task rolls the forearm joint (joint4, range +-178 deg) the short
// way towards the target orientation; when that orientation needs joint4 beyond its limit the
// joint is pinned by its velocity damper, the TCP stalls 5-12 cm / 3-7 deg short, and every
// later target inherits the posture. The same TCP pose exists on the other wrist branch:
// for three consecutive joints (roll a, bend b, roll c) whose roll axes are one line when
// q_b = 0 (a spherical wrist), (q_a +- pi, -q_b, q_c +- pi) leaves every later link in the
// same pose. The QP, a local method, never crosses q_b = 0 by itself (the orientation task
// holds the bend), so WristFlip does it above the QP:
//
//   start   an outer joint of a flip triple is within `margin` of a limit and not moving away
//           from it, the flipped triple has a larger smallest limit margin, the robot has not
//           arrived, no obstacle is within the influence distance and the arm is not held;
//   flip    the triple's rates are prescribed (straight line in joint space to the flipped
//           configuration, at most `speed`, within the joint bounds and dampers); the QP keeps
//           the TCP position task with the base and the other joints, the orientation rows are
//           left to the slack (the orientation returns exactly at the end of the flip);
//   end     within `tolerance` of the flipped configuration, or cancelled (QP failure,
//           obstacle within influence, arrival, arm held).
//
// Started early (margin 0.3 rad, the damper zone is 0.9 rad), the flip happens while the base
// still drives to a distant target: the trap is never entered and no time is lost.

#include "ehc_control/whole_body_model.h"

#include <Eigen/Core>

#include <string>
#include <vector>

namespace ehc_common {
class ConfigNode;
}  // namespace ehc_common

namespace ehc_control {

struct WristFlipParams {
  /// rad: an outer flip joint this close to a limit starts a flip; 0 = off.
  double margin = 0.3;
  double speed = 2.0;       ///< rad/s: rate of the triple's joint that moves most
  double gain = 4.0;        ///< 1/s: proportional approach to the flipped configuration (end of the flip)
  double tolerance = 0.02;  ///< rad: the flip ends this close to the flipped configuration
  void validate() const;    ///< throws "[WristFlipParams] ..."
  std::string summary() const;
};

/// First joints a of every flip triple (a, a+1, a+2) of the arm: joints a and a+2 turn about
/// one line when q_{a+1} = 0, so (q_a + pi, -q_{a+1}, q_{a+2} + pi) puts the TCP (and every
/// later link) in the same pose. Checked numerically on the model (several random postures).
std::vector<int> findFlipTriples(const WholeBodyModel& model);

class WristFlip {
 public:
  WristFlip(const WholeBodyModel& model, const WristFlipParams& params);

  /// Per cycle, before the QP: decides whether a flip starts (see the header comment; `may_run`
  /// is false when arrived, with an obstacle within influence, or with the arm held, and
  /// cancels a running flip), or ends. `last_arm_rates`: the arm rates of the previous command.
  /// Returns true while flipping; then rates() are the prescribed rates of joints first()..+2.
  bool update(const Eigen::VectorXd& q, const Eigen::VectorXd& last_arm_rates, bool may_run);
  /// Ends a running flip (e.g. the QP failed).
  void cancel() { active_ = -1; }
  bool active() const { return active_ >= 0; }
  int first() const { return active_; }                 ///< first joint of the running triple, -1 if none
  const Eigen::Vector3d& rates() const { return rates_; }  ///< rad/s, valid while active()
  const Eigen::Vector3d& goal() const { return goal_; }    ///< flipped configuration of the triple
  /// "" or what the last update() started ("wrist flip joint4..joint6: joint4 0.28 rad from its limit").
  const std::string& event() const { return event_; }
  const std::vector<int>& triples() const { return triples_; }
  const WristFlipParams& params() const { return params_; }
  long flips() const { return flips_; }                  ///< flips started so far

  /// The flipped configuration of triple `a` at q (each roll joint shifted by the +-pi with the
  /// larger limit margin), and its smallest limit margin (rad; negative: outside a limit).
  Eigen::Vector3d flipped(const Eigen::VectorXd& q, int a, double* min_margin) const;

 private:
  double margin(int joint, double value) const;  ///< distance to the nearer limit

  WristFlipParams params_;
  Eigen::VectorXd lower_, upper_;
  std::vector<std::string> names_;
  std::vector<int> triples_;
  int active_ = -1;
  Eigen::Vector3d goal_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d rates_ = Eigen::Vector3d::Zero();
  std::string event_;
  long flips_ = 0;
};

}  // namespace ehc_control
