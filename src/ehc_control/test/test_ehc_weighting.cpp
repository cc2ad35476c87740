// ReachabilityMap + EhcWeighting: the committed map matches the robot, sig(omega) is ~1 deep in
// the reachable set, ~0 for a target 3 m away, monotone along a ray; bad files and NaN rejected.

#include "ehc_control/ehc_weighting.h"
#include "ehc_test/control_fixtures.h"

#include <gtest/gtest.h>

#include <sys/resource.h>

#include <cstdlib>
#include <iostream>

#include <fstream>

using namespace ehc_control;

namespace {
std::shared_ptr<const ReachabilityMap> shippedMap() {
  static auto m = std::make_shared<const ReachabilityMap>(
      ReachabilityMap::load(test::realmanConfig().reachability_map_path));
  return m;
}
}  // namespace

TEST(ReachabilityMap, ShippedMapMatchesTheRobot) {
  const auto map = shippedMap();
  EXPECT_NO_THROW(map->checkCompatible(test::realmanConfig()));
  EXPECT_GT(map->countAbove(0.95), 500);   // a real region, not a handful of voxels
  EXPECT_GT(map->countAbove(0.0), 10000);
  // Far outside the arm's reach nothing is reachable.
  EXPECT_EQ(map->reachability(Eigen::Vector3d(2.0, 0, 0)), 0.0);
  EXPECT_EQ(map->reachability(Eigen::Vector3d(0, 0, std::nan(""))), 0.0);
}

TEST(ReachabilityMap, GenerationIsDeterministicPerSeedAndRoundTrips) {
  const WholeBodyModel model(test::realmanConfig());
  ReachabilityMapParams p;
  p.resolution = 0.1;
  const auto a = ReachabilityMap::generate(model, 20000, 5, p);
  const auto b = ReachabilityMap::generate(model, 20000, 5, p);
  const auto c = ReachabilityMap::generate(model, 20000, 6, p);
  a.save("/tmp/ehc_test_map.bin");
  const auto r = ReachabilityMap::load("/tmp/ehc_test_map.bin");
  int differs = 0;
  for (double x = -0.7; x <= 0.7; x += 0.1)
    for (double y = -0.7; y <= 0.7; y += 0.1)
      for (double z = -0.4; z <= 1.0; z += 0.1) {
        const Eigen::Vector3d pt(x, y, z);
        ASSERT_EQ(a.reachability(pt), b.reachability(pt));
        ASSERT_EQ(a.reachability(pt), r.reachability(pt));
        differs += a.reachability(pt) != c.reachability(pt);
      }
  EXPECT_GT(differs, 0);
  EXPECT_EQ(r.samples(), 20000);
  EXPECT_EQ(r.seed(), 5u);
}

// The map records the joint limits it sampled and the TCP at reference configurations; a model
// whose TCP or limits differ is found out, by start-up (checkCompatible) and by
// `ehc_kinematics --check` (kinematicMismatch).
TEST(ReachabilityMap, RecordsItsArmsKinematicsAndFindsAnotherArm) {
  const RobotConfig rc = test::realmanConfig();
  const WholeBodyModel model(rc);
  ReachabilityMapParams p;
  p.resolution = 0.1;
  ReachabilityMap::generate(model, 2000, 5, p).save("/tmp/ehc_test_kin_map.bin");
  const auto map = ReachabilityMap::load("/tmp/ehc_test_kin_map.bin");
  ASSERT_TRUE(map.hasKinematics());
  EXPECT_EQ(map.referencePoses().size(), static_cast<std::size_t>(ReachabilityMap::kReferencePoses));
  EXPECT_EQ(map.sampledLower(), rc.arm_lower);
  EXPECT_EQ(map.sampledUpper(), rc.arm_upper);
  EXPECT_EQ(map.kinematicMismatch(model), "");
  EXPECT_NO_THROW(map.checkCompatible(model));
  for (const auto& r : map.referencePoses()) {  // spread inside the limits, stored exactly
    EXPECT_TRUE((r.q.array() >= rc.arm_lower.array()).all() && (r.q.array() <= rc.arm_upper.array()).all());
    const Eigen::Isometry3d T = model.linkPoseInBase(r.q, rc.arm_base_frame).inverse() * model.linkPoseInBase(r.q, rc.tcp_frame);
    EXPECT_LT((T.translation() - r.tcp.translation()).norm(), 1e-12);
  }
  RobotConfig longer_tcp = rc;  // a TCP 3 cm further out: 0.3 voxel
  for (auto& c : longer_tcp.calibration)
    if (c.joint == "tcp_joint") c.xyz.z() += 0.03;
  const WholeBodyModel other(longer_tcp);
  EXPECT_NE(map.kinematicMismatch(other).find("the TCP at reference configuration"), std::string::npos)
      << map.kinematicMismatch(other);
  const std::string e = test::errorOf([&] { map.checkCompatible(other); });
  EXPECT_NE(e.find("built for another arm"), std::string::npos) << e;
  RobotConfig narrower = rc;
  narrower.arm_upper[4] -= 0.1;
  EXPECT_NE(map.kinematicMismatch(WholeBodyModel(narrower)).find("joint joint5 has limits"), std::string::npos);
}

TEST(ReachabilityMap, BadFilesFailClearly) {
  EXPECT_THROW(ReachabilityMap::load("/nonexistent.bin"), std::invalid_argument);
  std::ofstream("/tmp/ehc_bad_map.bin") << "not a map\n";
  EXPECT_THROW(ReachabilityMap::load("/tmp/ehc_bad_map.bin"), std::invalid_argument);
  // Truncated voxel data.
  std::ifstream in(test::realmanConfig().reachability_map_path, std::ios::binary);
  std::string all((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::ofstream("/tmp/ehc_bad_map.bin", std::ios::binary) << all.substr(0, all.size() / 2);
  try {
    ReachabilityMap::load("/tmp/ehc_bad_map.bin");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("truncated"), std::string::npos) << e.what();
  }
  RobotConfig other = test::realmanConfig();
  other.name = "other_robot";
  EXPECT_THROW(shippedMap()->checkCompatible(other), std::invalid_argument);
}

// A header claiming 2000^3 voxels allocated 7.9 GB before it was rejected.
// The load runs in a child process whose address space is capped at +512 MB over its current
// size: it must fail with the size named, not with an allocation failure.
[[noreturn]] void loadWithCappedMemory(const std::string& path) {
  long pages = 0;
  std::ifstream("/proc/self/statm") >> pages;
  const rlim_t cap = static_cast<rlim_t>(pages) * 4096 + (512ul << 20);
  rlimit lim{};
  lim.rlim_cur = cap;
  lim.rlim_max = cap;
  setrlimit(RLIMIT_AS, &lim);
  try {
    ReachabilityMap::load(path);
  } catch (const std::invalid_argument& e) {
    std::cerr << e.what() << std::endl;
    std::exit(std::string(e.what()).find("8000000000 voxels") != std::string::npos ? 0 : 3);
  } catch (const std::exception& e) {
    std::cerr << "unexpected: " << e.what() << std::endl;
    std::exit(4);
  }
  std::exit(5);
}

TEST(ReachabilityMap, HugeHeaderIsRejectedBeforeAllocating) {
  std::ifstream in(test::realmanConfig().reachability_map_path, std::ios::binary);
  std::string all((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto dims = all.find("\ndims ");
  ASSERT_NE(dims, std::string::npos);
  const auto eol = all.find('\n', dims + 1);
  all = all.substr(0, dims) + "\ndims 2000 2000 2000" + all.substr(eol);
  std::ofstream("/tmp/ehc_huge_map.bin", std::ios::binary) << all;
  ::testing::FLAGS_gtest_death_test_style = "threadsafe";
  EXPECT_EXIT(loadWithCappedMemory("/tmp/ehc_huge_map.bin"), ::testing::ExitedWithCode(0),
              "8000000000 voxels");
}

TEST(EhcWeighting, DeepInsideTheReachableSetTheArmLeads) {
  const EhcWeighting w(shippedMap(), EhcWeightingParams{});
  // Find the point of r_td with the most r_td neighbours within 15 cm: "deep inside".
  Eigen::Vector3d best = Eigen::Vector3d::Zero();
  int best_n = -1;
  for (double x = -0.5; x <= 0.5; x += 0.05)
    for (double y = -0.5; y <= 0.5; y += 0.05)
      for (double z = -0.2; z <= 0.8; z += 0.05) {
        const Eigen::Vector3d p(x, y, z);
        if (!w.inReachSet(p)) continue;
        int n = 0;
        for (double dx = -0.15; dx <= 0.151; dx += 0.05)
          for (double dy = -0.15; dy <= 0.151; dy += 0.05)
            for (double dz = -0.15; dz <= 0.151; dz += 0.05) n += w.inReachSet(p + Eigen::Vector3d(dx, dy, dz));
        if (n > best_n) best_n = n, best = p;
      }
  ASSERT_GT(best_n, 100);
  const EhcWeight ew = w.evaluate(best + Eigen::Vector3d(-0.05, 0, 0), best);
  EXPECT_GT(ew.omega, 1.5);
  EXPECT_GT(ew.sig, 0.99);
}

TEST(EhcWeighting, FarTargetTheBaseLeads) {
  const EhcWeighting w(shippedMap(), EhcWeightingParams{});
  const Eigen::Vector3d tcp(0.35, 0.0, 0.4);  // TCP in front of the arm
  const EhcWeight ew = w.evaluate(tcp, tcp + Eigen::Vector3d(3.0, 0.0, -0.2));
  EXPECT_LT(ew.omega, 0.3);
  EXPECT_LT(ew.sig, 0.01);
}

TEST(EhcWeighting, MonotoneInDistanceAlongARay) {
  const EhcWeighting w(shippedMap(), EhcWeightingParams{});
  for (const Eigen::Vector3d& dir : {Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0.6, 0.8, 0),
                                    Eigen::Vector3d(0.7, 0, -0.7).normalized()}) {
    const Eigen::Vector3d tcp(0.1, 0.0, 0.3);
    double prev = 2.0;
    int strictly = 0;
    for (double d = 0.05; d <= 3.0; d += 0.05) {
      const double s = w.evaluate(tcp, tcp + d * dir).sig;
      EXPECT_LE(s, prev + 1e-12) << "distance " << d;
      strictly += s < prev - 1e-6;
      prev = s;
    }
    EXPECT_GT(strictly, 3);  // it really goes down
  }
}

TEST(EhcWeighting, RejectsNaNAndBadParams) {
  const EhcWeighting w(shippedMap(), EhcWeightingParams{});
  EXPECT_THROW(w.evaluate(Eigen::Vector3d(std::nan(""), 0, 0), Eigen::Vector3d::Zero()), std::invalid_argument);
  EhcWeightingParams bad;
  bad.reach_threshold = 1.5;
  EXPECT_THROW(EhcWeighting(shippedMap(), bad), std::invalid_argument);
  EXPECT_THROW(EhcWeighting(nullptr, EhcWeightingParams{}), std::invalid_argument);
  EXPECT_NEAR(w.sig(1.0), 0.5, 1e-12);
}
