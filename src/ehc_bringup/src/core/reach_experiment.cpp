#include "ehc_bringup/reach_experiment.h"
#include "ehc_common/output_dir.h"
#include "ehc_common/stop_signal.h"

#include "ehc_common/bench_util.h"
#include "ehc_common/enum_names.h"

#include <chrono>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <stdexcept>
#include <sys/stat.h>

namespace ehc_bringup {

using ehc_control::ControlCycle;
using ehc_control::Vector6d;

namespace {
const char* kOwner = "ReachExperiment";
constexpr ehc_common::EnumNames<ReachProtocol, 2> kProtocolNames = {{
    {ReachProtocol::Sequence, "sequence"},
    {ReachProtocol::Reset, "reset"},
}};
constexpr ehc_common::EnumNames<ReachFailure, 8> kFailureNames = {{
    {ReachFailure::None, "none"},
    {ReachFailure::Unreachable, "unreachable"},
    {ReachFailure::Converging, "converging"},
    {ReachFailure::RollWinding, "roll_winding"},
    {ReachFailure::JointLimit, "joint_limit"},
    {ReachFailure::Singular, "singular"},
    {ReachFailure::BaseStuck, "base_stuck"},
    {ReachFailure::Stalled, "stalled"},
}};
}  // namespace

std::string toString(ReachProtocol p) { return ehc_common::enumName(kProtocolNames, p, kOwner); }
ReachProtocol reachProtocolFromString(const std::string& s) {
  return ehc_common::enumValue(kProtocolNames, s, kOwner, "protocol");
}
std::string toString(ReachFailure f) { return ehc_common::enumName(kFailureNames, f, kOwner); }
ReachFailure reachFailureFromString(const std::string& s) {
  return ehc_common::enumValue(kFailureNames, s, kOwner, "failure cause");
}
std::vector<ReachFailure> reachFailures() { return ehc_common::enumValues(kFailureNames); }

void ReachExperimentParams::validate() const {
  auto bad = [](const std::string& w) { throw std::invalid_argument("[ReachExperiment] " + w); };
  if (!(control_rate >= 1.0 && control_rate <= 10000.0)) bad("control_rate must be in [1, 10000] Hz");
  if (!(time_limit > 0.0)) bad("time_limit must be > 0");
  if (first_set < 0) bad("first_set must be >= 0");
  if (!(distant_threshold > 0.0)) bad("distant_threshold must be > 0");
  if (!(arrival_position > 0.0 && arrival_orientation > 0.0)) bad("arrival tolerances must be > 0");
  if (!(progress_window > 0.0 && progress_position > 0.0 && progress_orientation > 0.0))
    bad("progress_window, progress_position and progress_orientation must be > 0");
  if (!(base_reach > 0.0 && base_stuck_distance > 0.0)) bad("base_reach and base_stuck_distance must be > 0");
  noise.validate();
  motion_limit.validate();
  base_model.validate();
  servo.validate();
}

ReachExperiment::ReachExperiment(std::shared_ptr<const ehc_control::WholeBodyModel> model,
                                 const ehc_control::QpControllerParams& controller,
                                 std::shared_ptr<const ehc_control::EhcWeighting> weighting,
                                 const ReachExperimentParams& params)
    : model_(std::move(model)), controller_(controller), weighting_(std::move(weighting)),
      params_(params) {
  params_.validate();
  controller_.validate();
  cycle_params_.controller = controller_;
  cycle_params_.servo_type = ehc_control::ServoType::Proportional;
  cycle_params_.servo = params_.servo;
  cycle_params_.watchdog.require_obstacles = false;  // Exp-1 reaches in free space: no obstacle sensing
  cycle_params_.motion_limit = params_.motion_limit;
  roll_joint_ = ehc_control::findRollJoint(*model_);
  limits_ = std::make_unique<ehc_control::MotionLimitMonitor>(*model_, controller_, cycle_params_.motion_limit);
}

CommandSpeeds commandSpeeds(const Eigen::VectorXd& v, int nb) {
  CommandSpeeds c;
  c.base_t = nb == 3 ? std::hypot(v[0], v[1]) : std::abs(v[0]);
  c.base_r = std::abs(v[nb - 1]);
  c.arm = v.tail(v.size() - nb).cwiseAbs().sum();
  return c;
}
void accumulateSpeed(SpeedMeans& s, const Eigen::VectorXd& v, int nb) {
  const CommandSpeeds c = commandSpeeds(v, nb);
  s.base_t += c.base_t;
  s.base_r += c.base_r;
  s.arm += c.arm;
  ++s.cycles;
}
SpeedMeans meanSpeed(const SpeedMeans& s) {
  SpeedMeans m = s;
  if (s.cycles > 0) {
    m.base_t /= static_cast<double>(s.cycles);
    m.base_r /= static_cast<double>(s.cycles);
    m.arm /= static_cast<double>(s.cycles);
  }
  return m;
}

namespace {
double limitMargin(const ehc_control::RobotConfig& rc, const Eigen::VectorXd& q) {
  return std::min((q - rc.arm_lower).minCoeff(), (rc.arm_upper - q).minCoeff());
}
}  // namespace

void ReachExperiment::classifyFailure(ReachTrial& t, const Eigen::Vector3d& base, const Eigen::VectorXd& q,
                                      const Eigen::Isometry3d& target, double position_error_before,
                                      double orientation_error_before, const Eigen::Vector3d& base_before) const {
  const auto& rc = model_->config();
  t.failure_joint.clear();
  const int pinned = limits_->pinned(q);  // the joint closest to a limit, if pinned
  if (!kinematicallyReachable(*model_, target, controller_.joint_stop)) t.failure = ReachFailure::Unreachable;
  else if (position_error_before - t.final_position_error > params_.progress_position ||
           orientation_error_before - t.final_orientation_error > params_.progress_orientation)
    t.failure = ReachFailure::Converging;
  else if (pinned >= 0) t.failure = pinned == roll_joint_ ? ReachFailure::RollWinding : ReachFailure::JointLimit;
  else if (limits_->singular(q))
    t.failure = ReachFailure::Singular;
  else if (t.final_position_error > params_.base_reach &&
           (base - base_before).head<2>().norm() < params_.base_stuck_distance)
    t.failure = ReachFailure::BaseStuck;
  else t.failure = ReachFailure::Stalled;
  if (t.failure == ReachFailure::RollWinding || t.failure == ReachFailure::JointLimit)
    t.failure_joint = rc.arm_joints[static_cast<std::size_t>(pinned)];
}

ReachTrial ReachExperiment::reach(ehc_sim::KinematicFakeRobot& robot, ControlCycle& cycle,
                                  const Eigen::Isometry3d& target, SpeedMeans& distant,
                                  SpeedMeans& close, std::vector<double>& step_us) {
  const auto& rc = model_->config();
  const double dt = 1.0 / params_.control_rate;
  const int max_steps = static_cast<int>(std::ceil(params_.time_limit * params_.control_rate));
  ReachTrial t;
  t.min_joint_limit_margin = limitMargin(rc, robot.armPositions());
  // Errors and base position per cycle, for the failure classification at the end.
  const int window = std::max(1, static_cast<int>(std::lround(params_.progress_window * params_.control_rate)));
  std::vector<Eigen::Vector3d> history(static_cast<std::size_t>(window), Eigen::Vector3d::Zero());
  std::vector<Eigen::Vector2d> base_history(static_cast<std::size_t>(window), Eigen::Vector2d::Zero());
  bool recovering = false;
  for (int k = 0; k <= max_steps; ++k) {
    const Eigen::Isometry3d tcp = model_->fk(robot.basePose(), robot.armPositions(), rc.tcp_frame);
    const Vector6d e = ehc_control::poseError(tcp, target);
    t.final_position_error = e.head<3>().norm();
    t.final_orientation_error = e.tail<3>().norm();
    const std::size_t slot = static_cast<std::size_t>(k % window);
    if (k == max_steps) {
      const std::size_t before = k >= window ? slot : 0;  // the entry written `window` cycles ago
      classifyFailure(t, robot.basePose(), robot.armPositions(), target, history[before].x(), history[before].y(),
                      Eigen::Vector3d(base_history[before].x(), base_history[before].y(), 0.0));
    }
    history[slot] = Eigen::Vector3d(t.final_position_error, t.final_orientation_error, 0.0);
    base_history[slot] = robot.basePose().head<2>();
    if (t.final_position_error < params_.arrival_position &&
        t.final_orientation_error < params_.arrival_orientation) {
      t.reached = true;
      t.failure = ReachFailure::None;
      t.time_s = k * dt;
      return t;
    }
    if (k == max_steps) break;
    // The robot's state and the target, stamped with the sim time (a new target restarts the QP).
    const Eigen::VectorXd& q = robot.armPositions();
    const auto check = [](const std::string& err) {
      if (!err.empty()) throw std::runtime_error("[ReachExperiment] control cycle rejected an input: " + err);
    };
    check(cycle.setJointState(sim_time_, rc.arm_joints, std::vector<double>(q.data(), q.data() + q.size())));
    check(cycle.setBasePose(sim_time_, robot.odometryPose()));  // water2: what /odom would say
    check(cycle.setTarget(sim_time_, target));
    const auto t0 = std::chrono::steady_clock::now();
    const ehc_control::ControlCycleOutput out = cycle.update(sim_time_);
    step_us.push_back(std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count());
    sim_time_ += dt;
    const ehc_control::ControlCycleStatus& st = out.status;
    if (events_ && !out.event.empty())
      *events_ << ehc_control::toString(controller_.mode) << " set " << trace_set_ << " target " << trace_index_
               << " t " << k * dt << " s: " << out.event << "\n";
    if (st.recovering && !recovering) ++t.recoveries;  // a stall recovery (ReachRecovery) started
    recovering = st.recovering;
    if (st.qp_status != ehc_control::QpStatus::Ok) ++t.qp_failures;  // any cycle without a good QP solve
    if (trace_) {
      std::ostream& o = *trace_;
      o << ehc_control::toString(controller_.mode) << "," << trace_set_ << "," << trace_index_ << ","
        << k * dt << "," << robot.basePose().x() << "," << robot.basePose().y() << ","
        << robot.basePose().z();
      for (int i = 0; i < robot.armPositions().size(); ++i) o << "," << robot.armPositions()[i];
      o << "," << st.position_error << "," << st.orientation_error << "," << st.omega << ","
        << st.sig << "," << st.base_weight << "," << ehc_control::toString(st.qp_status);
      for (int i = 0; i < out.velocity.size(); ++i) o << "," << out.velocity[i];
      o << "\n";
    }
    accumulateSpeed(t.final_position_error > params_.distant_threshold ? distant : close, out.velocity,
               model_->nBase());
    robot.step(out.velocity, dt);
    t.min_joint_limit_margin = std::min(t.min_joint_limit_margin, limitMargin(rc, robot.armPositions()));
  }
  t.time_s = params_.time_limit;
  return t;
}

bool kinematicallyReachable(const ehc_control::WholeBodyModel& model, const Eigen::Isometry3d& target, double joint_stop) {
  return model.inverseKinematics(target, 1, 30, nullptr, nullptr, joint_stop);
}

ReachSummary ReachExperiment::run(const std::vector<std::vector<Eigen::Isometry3d>>& sets,
                                  unsigned seed, std::vector<ReachTrial>* trials,
                                  const Progress& progress) {
  const auto wall0 = std::chrono::steady_clock::now();
  ReachSummary s;
  s.method = ehc_control::toString(controller_.mode);
  s.base_model = ehc_sim::toString(params_.base_model.type);
  s.base_imprecision = params_.base_model.imprecision.level;
  int total = 0;
  for (const auto& set : sets) total += static_cast<int>(set.size());
  SpeedMeans distant, close;
  std::vector<double> step_us;
  double time_sum = 0.0;
  s.min_joint_limit_margin = 1e9;
  s.targets_planned = total;
  for (std::size_t si = 0; si < sets.size() && !s.partial; ++si) {
    const int set_number = params_.first_set + static_cast<int>(si);
    // Each set starts from nothing (controller state, clock), so a set rerun alone with
    // --first-set repeats it exactly.
    ControlCycle cycle(model_, weighting_, cycle_params_);
    sim_time_ = 0.0;
    const unsigned set_seed = seed + static_cast<unsigned>(set_number);
    ehc_sim::KinematicFakeRobot robot(model_->config(), params_.noise, set_seed, params_.base_model);
    robot.reset(Eigen::Vector3d::Zero(), model_->config().arm_ready, set_seed);
    for (std::size_t ti = 0; ti < sets[si].size(); ++ti) {
      if (ehc_common::stopRequested()) {  // SIGINT / SIGTERM: the targets reached so far
        s.partial = true;
        break;
      }
      if (params_.protocol == ReachProtocol::Reset && ti > 0)  // a fresh noise stream per target
        robot.reset(Eigen::Vector3d::Zero(), model_->config().arm_ready, set_seed * 1000u + static_cast<unsigned>(ti));
      trace_set_ = set_number;
      trace_index_ = static_cast<int>(ti);
      ReachTrial t = reach(robot, cycle, sets[si][ti], distant, close, step_us);
      t.method = s.method;
      t.set = set_number;
      t.index = static_cast<int>(ti);
      ++s.targets;
      if (t.reached) {
        time_sum += t.time_s;
      } else {
        ++s.failed;
        ++s.failures[t.failure];
        if (!t.failure_joint.empty()) ++s.pinned_joints[t.failure_joint];
      }
      s.qp_failures += t.qp_failures;
      s.recoveries += t.recoveries;
      s.min_joint_limit_margin = std::min(s.min_joint_limit_margin, t.min_joint_limit_margin);
      if (trials) trials->push_back(t);
      if (progress) {
        ReachSummary p = s;
        p.mean_time_s = s.targets > s.failed ? time_sum / (s.targets - s.failed) : 0.0;
        progress(s.targets, total, p);
      }
    }
  }
  s.mean_time_s = s.targets > s.failed ? time_sum / (s.targets - s.failed) : 0.0;
  s.distant = meanSpeed(distant);
  s.close = meanSpeed(close);
  s.cycles = distant.cycles + close.cycles;
  const ehc_common::BenchStats st = ehc_common::benchStats(step_us);
  s.controller_median_us = st.median_us;
  s.controller_p99_us = st.p99_us;
  s.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  return s;
}

ehc_common::Json speedJson(const SpeedMeans& m) {
  return {{"base_t", ehc_common::jsonNumber(m.base_t)},
          {"base_r", ehc_common::jsonNumber(m.base_r)},
          {"arm", ehc_common::jsonNumber(m.arm)},
          {"cycles", m.cycles}};
}

ehc_common::Json summaryJsonValue(const ReachSummary& s) {
  using ehc_common::jsonNumber;
  ehc_common::Json j;
  j["method"] = s.method;
  j["base_model"] = s.base_model;
  j["base_imprecision"] = jsonNumber(s.base_imprecision);
  j["targets"] = s.targets;
  j["failed"] = s.failed;
  j["mean_time_s"] = jsonNumber(s.mean_time_s);
  j["distant"] = speedJson(s.distant);
  j["close"] = speedJson(s.close);
  j["qp_failures"] = s.qp_failures;
  j["recoveries"] = s.recoveries;
  j["min_joint_limit_margin_rad"] = jsonNumber(s.min_joint_limit_margin);
  j["controller_step_median_us"] = jsonNumber(s.controller_median_us);
  j["controller_step_p99_us"] = jsonNumber(s.controller_p99_us);
  j["wall_time_s"] = jsonNumber(s.wall_time_s);
  j["partial"] = s.partial;
  j["targets_planned"] = s.targets_planned;
  ehc_common::Json& causes = j["failure_causes"] = ehc_common::Json::object();
  for (const ReachFailure f : reachFailures()) {
    if (f == ReachFailure::None) continue;
    const auto it = s.failures.find(f);
    causes[toString(f)] = it == s.failures.end() ? 0 : it->second;
  }
  ehc_common::Json& pinned = j["pinned_joints"] = ehc_common::Json::object();
  for (const auto& [joint, n] : s.pinned_joints) pinned[joint] = n;
  return j;
}

std::string summaryJson(const ReachSummary& s) { return ehc_common::jsonLine(summaryJsonValue(s)); }

void writeReachResults(const std::string& dir, const std::vector<ReachSummary>& summaries,
                       const std::vector<ReachTrial>& trials, const std::string& notes) {
  ehc_common::prepareOutputDir(dir);
  auto open = [&](const std::string& name) {
    std::ofstream f(dir + "/" + name);
    if (!f) throw std::runtime_error("[ReachExperiment] cannot write " + dir + "/" + name);
    return f;
  };
  {
    std::ofstream f = open("summary.json");
    if (summaries.size() == 1) {
      f << summaryJson(summaries[0]) << "\n";
    } else {
      ehc_common::Json all = ehc_common::Json::array();
      for (const ReachSummary& m : summaries) all.push_back(summaryJsonValue(m));
      f << ehc_common::jsonLine(all) << "\n";
    }
  }
  {
    std::ofstream f = open("table.md");
    f << "| Method | Time(s) | Distant(Base-T/Base-R/Arm) | Close(Base-T/Base-R/Arm) | # of Failed (/"
      << (summaries.empty() ? 0 : summaries[0].targets) << ") |\n|---|---|---|---|---|\n"
      << std::fixed;
    for (const auto& s : summaries)
      f << "| " << s.method << " | " << std::setprecision(2) << s.mean_time_s << " | "
        << std::setprecision(3) << s.distant.base_t << "/" << s.distant.base_r << "/" << s.distant.arm
        << " | " << s.close.base_t << "/" << s.close.base_r << "/" << s.close.arm << " | " << s.failed
        << " |\n";
    // Failure causes (ReachFailure), per method.
    f << "\n| Method | Failed |";
    for (const ReachFailure c : reachFailures())
      if (c != ReachFailure::None) f << " " << toString(c) << " |";
    f << " pinned joints |\n|---|---|";
    for (const ReachFailure c : reachFailures())
      if (c != ReachFailure::None) f << "---|";
    f << "---|\n";
    for (const auto& s : summaries) {
      f << "| " << s.method << " | " << s.failed << " |";
      for (const ReachFailure c : reachFailures()) {
        if (c == ReachFailure::None) continue;
        const auto it = s.failures.find(c);
        f << " " << (it == s.failures.end() ? 0 : it->second) << " |";
      }
      std::string joints;
      for (const auto& [joint, n] : s.pinned_joints) joints += (joints.empty() ? "" : ", ") + joint + " " + std::to_string(n);
      f << " " << (joints.empty() ? "-" : joints) << " |\n";
    }
    if (!notes.empty()) f << "\n" << notes << "\n";
  }
  {
    std::ofstream f = open("trials.csv");
    f << "method,set,index,reached,time_s,final_position_error_m,final_orientation_error_rad,qp_failures,"
         "min_joint_limit_margin_rad,failure,failure_joint,recoveries\n";
    for (const auto& t : trials)
      f << t.method << "," << t.set << "," << t.index << "," << (t.reached ? 1 : 0) << "," << t.time_s << ","
        << t.final_position_error << "," << t.final_orientation_error << "," << t.qp_failures << ","
        << t.min_joint_limit_margin << "," << toString(t.failure) << "," << t.failure_joint << "," << t.recoveries << "\n";
  }
}

}  // namespace ehc_bringup
