#include "ehc_control/reachability_map.h"

#include <cmath>
#include <fstream>
#include <iomanip>
#include <random>
#include <sstream>
#include <stdexcept>

namespace ehc_control {

namespace {
[[noreturn]] void fail(const std::string& what) {
  throw std::invalid_argument("[ReachabilityMap] " + what);
}
// Format 2 adds the sampled joint limits and the reference poses; format 1 maps still load.
const char* kMagic = "EHC_REACHABILITY_MAP 2";
const char* kMagicV1 = "EHC_REACHABILITY_MAP 1";

/// Reference configuration k: spread over the joint ranges (fractional parts of multiples of
/// square roots of primes, one prime per joint), the same for every map of the same limits.
Eigen::VectorXd referenceConfiguration(int k, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper) {
  static const double kPrimes[] = {2, 3, 5, 7, 11, 13, 17, 19};
  Eigen::VectorXd q(lower.size());
  for (int i = 0; i < q.size(); ++i) {
    const double f = (k + 1) * std::sqrt(kPrimes[i % 8]);
    q[i] = lower[i] + (upper[i] - lower[i]) * (f - std::floor(f));
  }
  return q;
}

/// TCP pose in the arm base frame (the map's frame) at q.
Eigen::Isometry3d tcpInArmBase(const WholeBodyModel& model, const Eigen::VectorXd& q) {
  const RobotConfig& rc = model.config();
  return model.linkPoseInBase(q, rc.arm_base_frame).inverse() * model.linkPoseInBase(q, rc.tcp_frame);
}
}  // namespace

void ReachabilityMapParams::validate() const {
  if (!(resolution >= 0.005 && resolution <= 0.5)) fail("resolution must be in [0.005, 0.5] m");
  if (direction_bins < 1 || direction_bins > 255) fail("direction_bins must be in [1, 255]");
}

std::vector<Eigen::Vector3d> ReachabilityMap::directionSet(int bins) {
  std::vector<Eigen::Vector3d> d;
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < bins; ++i) {
    const double z = 1.0 - 2.0 * (i + 0.5) / bins;
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    d.emplace_back(r * std::cos(golden * i), r * std::sin(golden * i), z);
  }
  return d;
}

ReachabilityMap ReachabilityMap::generate(const WholeBodyModel& model, long samples, unsigned seed,
                                          const ReachabilityMapParams& params,
                                          const Progress& progress) {
  params.validate();
  if (samples < 1) fail("need at least one sample");
  const RobotConfig& rc = model.config();
  ReachabilityMap m;
  m.robot_name_ = rc.name;
  m.arm_base_frame_ = rc.arm_base_frame;
  m.tcp_frame_ = rc.tcp_frame;
  m.n_arm_ = rc.nArm();
  m.resolution_ = params.resolution;
  m.direction_bins_ = params.direction_bins;
  m.samples_ = samples;
  m.seed_ = seed;
  m.lower_ = rc.arm_lower;
  m.upper_ = rc.arm_upper;
  for (int k = 0; k < kReferencePoses; ++k) {
    ReferencePose r;
    r.q = referenceConfiguration(k, rc.arm_lower, rc.arm_upper);
    r.tcp = tcpInArmBase(model, r.q);
    m.references_.push_back(r);
  }

  // Grid bounds: a cube around the arm base large enough for the longest possible reach
  // (sum of distances between consecutive chain frames bounds the TCP distance).
  const Eigen::VectorXd q0 = Eigen::VectorXd::Zero(rc.nArm()).cwiseMax(rc.arm_lower).cwiseMin(rc.arm_upper);
  const Eigen::Isometry3d Tab = model.linkPoseInBase(q0, rc.arm_base_frame).inverse();
  std::mt19937_64 rng(seed);
  std::vector<std::uniform_real_distribution<double>> joint;
  for (int i = 0; i < rc.nArm(); ++i) joint.emplace_back(rc.arm_lower[i], rc.arm_upper[i]);
  double reach = 0.0;
  {
    std::mt19937_64 probe(seed ^ 0x9e3779b97f4a7c15ULL);
    Eigen::VectorXd q(rc.nArm());
    for (int k = 0; k < 20000; ++k) {
      for (int i = 0; i < rc.nArm(); ++i) q[i] = joint[static_cast<std::size_t>(i)](probe);
      reach = std::max(reach, (Tab * model.linkPoseInBase(q, rc.tcp_frame)).translation().norm());
    }
  }
  const double half = reach + 2.0 * params.resolution;
  const int n = static_cast<int>(std::ceil(2.0 * half / params.resolution));
  m.dims_ = Eigen::Vector3i(n, n, n);
  m.origin_ = Eigen::Vector3d::Constant(-0.5 * n * params.resolution);

  const std::vector<Eigen::Vector3d> dirs = directionSet(params.direction_bins);
  const long voxels = static_cast<long>(n) * n * n;
  std::vector<std::uint64_t> bits(static_cast<std::size_t>(voxels) * 4, 0);  // up to 256 bins
  Eigen::VectorXd q(rc.nArm());
  const long report_every = std::max(1L, samples / 200);
  for (long s = 0; s < samples; ++s) {
    for (int i = 0; i < rc.nArm(); ++i) q[i] = joint[static_cast<std::size_t>(i)](rng);
    const Eigen::Isometry3d T = Tab * model.linkPoseInBase(q, rc.tcp_frame);
    const long v = m.index(T.translation());
    if (v >= 0) {
      const Eigen::Vector3d z = T.linear().col(2);
      int best = 0;
      double best_dot = -2.0;
      for (int b = 0; b < params.direction_bins; ++b) {
        const double d = z.dot(dirs[static_cast<std::size_t>(b)]);
        if (d > best_dot) best_dot = d, best = b;
      }
      bits[static_cast<std::size_t>(v) * 4 + static_cast<std::size_t>(best / 64)] |= 1ULL << (best % 64);
    }
    if (progress && (s + 1) % report_every == 0) progress(s + 1, samples);
  }
  m.reached_.assign(static_cast<std::size_t>(voxels), 0);
  for (long v = 0; v < voxels; ++v) {
    int c = 0;
    for (int w = 0; w < 4; ++w) c += __builtin_popcountll(bits[static_cast<std::size_t>(v) * 4 + static_cast<std::size_t>(w)]);
    m.reached_[static_cast<std::size_t>(v)] = static_cast<std::uint8_t>(c);
  }
  if (progress) progress(samples, samples);
  return m;
}

long ReachabilityMap::index(const Eigen::Vector3d& p) const {
  const Eigen::Vector3d f = (p - origin_) / resolution_;
  const int x = static_cast<int>(std::floor(f.x())), y = static_cast<int>(std::floor(f.y())),
            z = static_cast<int>(std::floor(f.z()));
  if (!(x >= 0 && y >= 0 && z >= 0 && x < dims_.x() && y < dims_.y() && z < dims_.z())) return -1;
  return (static_cast<long>(z) * dims_.y() + y) * dims_.x() + x;
}

double ReachabilityMap::reachability(const Eigen::Vector3d& p_arm) const {
  if (!p_arm.allFinite() || direction_bins_ == 0) return 0.0;
  const long i = index(p_arm);
  return i < 0 ? 0.0 : static_cast<double>(reached_[static_cast<std::size_t>(i)]) / direction_bins_;
}

long ReachabilityMap::countAbove(double threshold) const {
  long c = 0;
  for (std::uint8_t r : reached_)
    if (static_cast<double>(r) / direction_bins_ > threshold) ++c;
  return c;
}

void ReachabilityMap::checkCompatible(const RobotConfig& robot) const {
  if (robot.name != robot_name_ || robot.arm_base_frame != arm_base_frame_ ||
      robot.tcp_frame != tcp_frame_ || robot.nArm() != n_arm_)
    fail("map was built for robot '" + robot_name_ + "' (" + arm_base_frame_ + " -> " + tcp_frame_ +
         ", " + std::to_string(n_arm_) + " joints), not for '" + robot.name + "' (" +
         robot.arm_base_frame + " -> " + robot.tcp_frame + ", " + std::to_string(robot.nArm()) +
         " joints); regenerate it with ehc_reachability");
}

void ReachabilityMap::checkCompatible(const WholeBodyModel& model) const {
  checkCompatible(model.config());
  const std::string mismatch = kinematicMismatch(model);
  if (!mismatch.empty())
    fail("map was built for another arm of robot '" + robot_name_ + "': " + mismatch +
         "; regenerate it with ehc_reachability");
}

std::string ReachabilityMap::kinematicMismatch(const WholeBodyModel& model) const {
  if (!hasKinematics()) return "";
  const RobotConfig& rc = model.config();
  if (rc.nArm() != n_arm_) return "the map has " + std::to_string(n_arm_) + " arm joints, the robot " + std::to_string(rc.nArm());
  std::ostringstream os;
  os << std::setprecision(6);
  for (int i = 0; i < n_arm_; ++i)
    if (std::abs(rc.arm_lower[i] - lower_[i]) > 1e-6 || std::abs(rc.arm_upper[i] - upper_[i]) > 1e-6) {
      os << "joint " << rc.arm_joints[static_cast<std::size_t>(i)] << " has limits [" << rc.arm_lower[i] << ", "
         << rc.arm_upper[i] << "] rad, the map sampled [" << lower_[i] << ", " << upper_[i] << "]";
      return os.str();
    }
  for (std::size_t k = 0; k < references_.size(); ++k) {
    const Eigen::Isometry3d T = tcpInArmBase(model, references_[k].q);
    const double dp = (T.translation() - references_[k].tcp.translation()).norm();
    const double da = Eigen::AngleAxisd(T.linear().transpose() * references_[k].tcp.linear()).angle();
    if (dp > 0.2 * resolution_ || da > 0.02) {
      os << "the TCP at reference configuration " << k << " is " << dp << " m and " << da
         << " rad from where the map's arm had it";
      return os.str();
    }
  }
  return "";
}

std::string ReachabilityMap::summary() const {
  std::ostringstream os;
  os << "reachability map of '" << robot_name_ << "' (" << arm_base_frame_ << " -> " << tcp_frame_
     << "): " << dims_.x() << "x" << dims_.y() << "x" << dims_.z() << " voxels of " << resolution_
     << " m, " << direction_bins_ << " direction bins, " << samples_ << " samples (seed " << seed_
     << "), " << countAbove(0.0) << " voxels reached, " << countAbove(0.95) << " with R > 0.95";
  return os.str();
}

void ReachabilityMap::save(const std::string& path) const {
  std::ofstream out(path, std::ios::binary);
  if (!out) fail("cannot write '" + path + "'");
  out << kMagic << "\n"
      << "robot " << robot_name_ << "\n"
      << "frames " << arm_base_frame_ << " " << tcp_frame_ << "\n"
      << "arm_joints " << n_arm_ << "\n"
      << std::setprecision(17) << "resolution " << resolution_ << "\n"
      << "origin " << origin_.x() << " " << origin_.y() << " " << origin_.z() << "\n"
      << "dims " << dims_.x() << " " << dims_.y() << " " << dims_.z() << "\n"
      << "direction_bins " << direction_bins_ << "\n"
      << "samples " << samples_ << "\n"
      << "seed " << seed_ << "\n";
  out << "limits";
  for (int i = 0; i < n_arm_; ++i) out << " " << lower_[i];
  for (int i = 0; i < n_arm_; ++i) out << " " << upper_[i];
  out << "\nreferences " << references_.size() << "\n";
  for (const ReferencePose& r : references_) {
    const Eigen::Quaterniond qt(r.tcp.linear());
    out << "reference";
    for (int i = 0; i < r.q.size(); ++i) out << " " << r.q[i];
    const Eigen::Vector3d& t = r.tcp.translation();
    out << " " << t.x() << " " << t.y() << " " << t.z() << " " << qt.x() << " " << qt.y() << " " << qt.z() << " "
        << qt.w() << "\n";
  }
  out << "data\n";
  out.write(reinterpret_cast<const char*>(reached_.data()), static_cast<std::streamsize>(reached_.size()));
  if (!out) fail("error while writing '" + path + "'");
}

void ReachabilityMap::readKinematics(const std::string& path,
                                     const std::function<std::string(const std::string&)>& expect) {
  if (n_arm_ < 1 || n_arm_ > 7) fail("'" + path + "': invalid header values (arm_joints)");
  auto numbers = [&](const std::string& key, int n) {
    std::istringstream ss(expect(key));
    std::vector<double> v(static_cast<std::size_t>(n));
    for (double& x : v)
      if (!(ss >> x) || !std::isfinite(x)) fail("'" + path + "': line '" + key + "' needs " + std::to_string(n) + " finite numbers");
    std::string rest;
    if (ss >> rest) fail("'" + path + "': line '" + key + "' has more than " + std::to_string(n) + " numbers");
    return v;
  };
  const std::vector<double> limits = numbers("limits", 2 * n_arm_);
  lower_ = Eigen::Map<const Eigen::VectorXd>(limits.data(), n_arm_);
  upper_ = Eigen::Map<const Eigen::VectorXd>(limits.data() + n_arm_, n_arm_);
  const std::vector<double> count = numbers("references", 1);
  if (count[0] < 1 || count[0] > 100 || count[0] != std::floor(count[0]))
    fail("'" + path + "': invalid header values (references)");
  for (int k = 0; k < static_cast<int>(count[0]); ++k) {
    const std::vector<double> v = numbers("reference", n_arm_ + 7);
    ReferencePose r;
    r.q = Eigen::Map<const Eigen::VectorXd>(v.data(), n_arm_);
    const double* t = v.data() + n_arm_;
    r.tcp.translation() << t[0], t[1], t[2];
    r.tcp.linear() = Eigen::Quaterniond(t[6], t[3], t[4], t[5]).normalized().toRotationMatrix();
    references_.push_back(r);
  }
}

ReachabilityMap ReachabilityMap::load(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail("cannot read map file '" + path + "'");
  std::string line;
  std::getline(in, line);
  if (line != kMagic && line != kMagicV1) fail("'" + path + "' is not a reachability map (bad header)");
  const bool v1 = line == kMagicV1;
  ReachabilityMap m;
  auto expect = [&](const std::string& key) {
    if (!std::getline(in, line)) fail("'" + path + "' is truncated before '" + key + "'");
    std::istringstream ss(line);
    std::string k;
    ss >> k;
    if (k != key) fail("'" + path + "': expected '" + key + "', got '" + line + "'");
    return std::string(line.begin() + static_cast<long>(key.size()), line.end());
  };
  std::istringstream(expect("robot")) >> m.robot_name_;
  std::istringstream(expect("frames")) >> m.arm_base_frame_ >> m.tcp_frame_;
  std::istringstream(expect("arm_joints")) >> m.n_arm_;
  std::istringstream(expect("resolution")) >> m.resolution_;
  std::istringstream(expect("origin")) >> m.origin_.x() >> m.origin_.y() >> m.origin_.z();
  std::istringstream(expect("dims")) >> m.dims_.x() >> m.dims_.y() >> m.dims_.z();
  std::istringstream(expect("direction_bins")) >> m.direction_bins_;
  std::istringstream(expect("samples")) >> m.samples_;
  std::istringstream(expect("seed")) >> m.seed_;
  if (!v1) m.readKinematics(path, expect);
  expect("data");
  if (!(m.resolution_ > 0) || (m.dims_.array() <= 0).any() || (m.dims_.array() > 2000).any() ||
      m.direction_bins_ < 1 || m.direction_bins_ > 255 || !m.origin_.allFinite())
    fail("'" + path + "': invalid header values");
  const std::size_t voxels = static_cast<std::size_t>(m.dims_.x()) * m.dims_.y() * m.dims_.z();
  // The header's size is checked against the bytes the file holds before anything is allocated
  // (a header claiming 2000^3 voxels must not allocate 8 GB to find out).
  const std::streamoff data_start = in.tellg();
  in.seekg(0, std::ios::end);
  const std::streamoff data_bytes = in.tellg() - data_start;
  in.seekg(data_start);
  if (data_start < 0 || data_bytes < 0 || !in ||
      static_cast<std::size_t>(data_bytes) != voxels)
    fail("'" + path + "' is truncated or oversized: the header claims " + std::to_string(voxels) +
         " voxels but the file holds " + std::to_string(data_bytes) + " bytes of voxel data");
  m.reached_.resize(voxels);
  in.read(reinterpret_cast<char*>(m.reached_.data()), static_cast<std::streamsize>(voxels));
  if (static_cast<std::size_t>(in.gcount()) != voxels) fail("'" + path + "' is truncated (voxel data)");
  for (std::uint8_t r : m.reached_)
    if (r > m.direction_bins_) fail("'" + path + "': corrupt voxel data");
  return m;
}

}  // namespace ehc_control
