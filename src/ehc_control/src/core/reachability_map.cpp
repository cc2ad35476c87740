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
const char* kMagic = "EHC_REACHABILITY_MAP 1";
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
      << "seed " << seed_ << "\n"
      << "data\n";
  out.write(reinterpret_cast<const char*>(reached_.data()), static_cast<std::streamsize>(reached_.size()));
  if (!out) fail("error while writing '" + path + "'");
}

ReachabilityMap ReachabilityMap::load(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail("cannot read map file '" + path + "'");
  std::string line;
  std::getline(in, line);
  if (line != kMagic) fail("'" + path + "' is not a reachability map (bad header)");
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
