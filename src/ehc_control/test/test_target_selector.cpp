// TargetSelector: on randomized scenes (seed printed) the selected object is the one each rule
// names, checked against a brute-force count in the camera's heading frame; ambiguous scenes,
// empty views and too few objects give their status; bad selector configs name file and field.

#include "ehc_common/config_node.h"
#include "ehc_control/target_selector.h"
#include "ehc_test/errors.h"

#include <gtest/gtest.h>

#include <iostream>
#include <random>

namespace ehc_control {
namespace {

using ehc_common::ConfigNode;
using ehc_test::errorOf;

/// Camera at `pos` with heading `yaw` (about world z), pitched `pitch` down (optical z forward).
Eigen::Isometry3d camera(const Eigen::Vector3d& pos, double yaw, double pitch) {
  Eigen::Matrix3d level;  // optical frame looking along world x: z = x, x = -y, y = -z
  level << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix() *
               Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()).toRotationMatrix() * level;
  T.translation() = pos;
  return T;
}

struct Scene {
  Eigen::Isometry3d cam;
  double yaw = 0.0;
  std::vector<Eigen::Vector3d> centres;
};

Scene randomScene(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Scene s;
  s.yaw = (u(rng) * 2.0 - 1.0) * M_PI;
  const Eigen::Vector3d cam_pos(u(rng) * 2.0 - 1.0, u(rng) * 2.0 - 1.0, 1.0 + 0.5 * u(rng));
  s.cam = camera(cam_pos, s.yaw, (10.0 + 60.0 * u(rng)) * M_PI / 180.0);
  const Eigen::Vector3d heading(std::cos(s.yaw), std::sin(s.yaw), 0.0), side(-std::sin(s.yaw), std::cos(s.yaw), 0.0);
  const int n = 1 + static_cast<int>(u(rng) * 6.0);
  for (int i = 0; i < n; ++i) {
    const double ahead = 0.4 + 0.8 * u(rng), across = (u(rng) - 0.5) * 0.8, h = 0.75 + 0.1 * u(rng);
    Eigen::Vector3d c = cam_pos + ahead * heading + across * side;
    c.z() = h;
    s.centres.push_back(c);
  }
  return s;
}

/// In the camera's heading frame: x forward, y left (brute force, independent of the selector).
Eigen::Vector2d headingFrame(const Scene& s, const Eigen::Vector3d& c) {
  const Eigen::Vector3d d = c - s.cam.translation();
  return Eigen::Vector2d(d.x() * std::cos(s.yaw) + d.y() * std::sin(s.yaw), -d.x() * std::sin(s.yaw) + d.y() * std::cos(s.yaw));
}

TEST(TargetSelector, RandomScenesSelectTheObjectEachRuleNames) {
  const unsigned seed = 20261127;
  std::cout << "[ seed     ] " << seed << std::endl;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int selected = 0, ambiguous = 0, too_few = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    const Scene s = randomScene(rng);
    TargetSelector sel;
    sel.kind = static_cast<TargetSelectorKind>(1 + trial % 3);
    sel.k = 1 + static_cast<int>(u(rng) * 4.0);
    sel.point = s.centres[0] + Eigen::Vector3d(u(rng) - 0.5, u(rng) - 0.5, 0.0) * 0.6;
    const TargetSelection r = selectTarget(sel, s.centres, s.cam);
    SCOPED_TRACE("seed " + std::to_string(seed) + " trial " + std::to_string(trial) + ": " + sel.summary() + ": " + r.detail);
    // The quantity each rule ranks, smallest first, and how many objects rank before the answer.
    auto key = [&](const Eigen::Vector3d& c) {
      const Eigen::Vector2d h = headingFrame(s, c);
      if (sel.kind == TargetSelectorKind::Nearest) return (c - sel.point).norm();
      return sel.kind == TargetSelectorKind::KthFromLeft ? -h.y() : h.x();
    };
    const int want = sel.kind == TargetSelectorKind::Nearest ? 1 : sel.k;
    if (want > static_cast<int>(s.centres.size())) {
      EXPECT_EQ(r.status, TargetSelectionStatus::TooFewObjects);
      ++too_few;
      continue;
    }
    if (r.status == TargetSelectionStatus::Ambiguous) {  // some object is within the margin of the k-th
      ++ambiguous;
      std::vector<double> keys;
      for (const auto& c : s.centres) keys.push_back(key(c));
      std::sort(keys.begin(), keys.end());
      const auto w = static_cast<std::size_t>(want - 1);
      const bool close = (w > 0 && keys[w] - keys[w - 1] < sel.ambiguity) ||
                         (w + 1 < keys.size() && keys[w + 1] - keys[w] < sel.ambiguity);
      EXPECT_TRUE(close);
      continue;
    }
    ASSERT_EQ(r.status, TargetSelectionStatus::Selected);
    ++selected;
    const double chosen = key(s.centres[static_cast<std::size_t>(r.index)]);
    int before = 0;
    for (const auto& c : s.centres) {
      if (key(c) < chosen) ++before;
      if (&c != &s.centres[static_cast<std::size_t>(r.index)]) EXPECT_GE(std::abs(key(c) - chosen), sel.ambiguity);
    }
    EXPECT_EQ(before, want - 1);
    EXPECT_TRUE(r.centre.isApprox(s.centres[static_cast<std::size_t>(r.index)]));
  }
  std::cout << "[ scenes   ] selected " << selected << ", ambiguous " << ambiguous << ", too few " << too_few << std::endl;
  EXPECT_GT(selected, 1500);
  EXPECT_GT(ambiguous, 0);
  EXPECT_GT(too_few, 0);
}

TEST(TargetSelector, LeftAndFrontFollowTheCameraNotTheWorld) {
  // Camera at the origin looking along world -y (turned right): its left is world +x.
  const Eigen::Isometry3d cam = camera(Eigen::Vector3d(0, 0, 1.2), -M_PI / 2, 0.6);
  const std::vector<Eigen::Vector3d> c = {{0.3, -0.6, 0.8}, {-0.2, -0.9, 0.8}, {0.0, -1.2, 0.8}};
  TargetSelector s;
  s.kind = TargetSelectorKind::KthFromLeft;
  EXPECT_EQ(selectTarget(s, c, cam).index, 0);
  s.k = 3;
  EXPECT_EQ(selectTarget(s, c, cam).index, 1);
  s.kind = TargetSelectorKind::KthFromFront;
  s.k = 1;
  EXPECT_EQ(selectTarget(s, c, cam).index, 0);
  s.k = 3;
  EXPECT_EQ(selectTarget(s, c, cam).index, 2);
  // Looking straight down after pitching from the heading +x: front is still +x (image up).
  const Eigen::Isometry3d down = camera(Eigen::Vector3d(0, 0, 1.5), 0.0, M_PI / 2);
  s.k = 1;
  EXPECT_EQ(selectTarget(s, {{0.1, 0, 0.8}, {-0.1, 0, 0.8}}, down).index, 1);
}

TEST(TargetSelector, NoObjectAmbiguityAndTagsGiveAStatusWithAReason) {
  const Eigen::Isometry3d cam = camera(Eigen::Vector3d::Zero(), 0.0, 0.5);
  TargetSelector s;
  s.kind = TargetSelectorKind::Nearest;
  s.point = Eigen::Vector3d(1, 0, 0.8);
  TargetSelection r = selectTarget(s, {}, cam);
  EXPECT_EQ(r.status, TargetSelectionStatus::NoObject);
  EXPECT_NE(r.detail.find("no object in the view"), std::string::npos) << r.detail;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(selectTarget(s, {Eigen::Vector3d(nan, 0, 0)}, cam).status, TargetSelectionStatus::NoObject);
  r = selectTarget(s, {{1, 0.1, 0.8}, {1, -0.105, 0.8}}, cam);  // 5 mm apart in distance to the point
  EXPECT_EQ(r.status, TargetSelectionStatus::Ambiguous);
  EXPECT_NE(r.detail.find("ambiguous"), std::string::npos) << r.detail;
  s.radius = 0.05;  // the only object in the view is 0.2 m from the point: not it
  r = selectTarget(s, {{1, 0.2, 0.8}}, cam);
  EXPECT_EQ(r.status, TargetSelectionStatus::NoObject);
  EXPECT_NE(r.detail.find("within the radius"), std::string::npos) << r.detail;
  EXPECT_EQ(selectTarget(s, {{1, 0.2, 0.8}, {1, 0.03, 0.8}}, cam).index, 1);
  s.kind = TargetSelectorKind::KthFromLeft;
  s.k = 3;
  r = selectTarget(s, {{1, 0.1, 0.8}, {1, -0.1, 0.8}}, cam);
  EXPECT_EQ(r.status, TargetSelectionStatus::TooFewObjects);
  EXPECT_NE(r.detail.find("only 2 object(s)"), std::string::npos) << r.detail;
  s.kind = TargetSelectorKind::Tag;
  EXPECT_EQ(selectTarget(s, {{1, 0, 0.8}}, cam).status, TargetSelectionStatus::NotCloudTarget);
  EXPECT_EQ(toString(TargetSelectionStatus::Ambiguous), "ambiguous");
}

TEST(TargetSelector, CloudTargetPoseLooksFromTheViewpointHorizontally) {
  const Eigen::Isometry3d T = cloudTargetPose(Eigen::Vector3d(1, 1, 0.8), Eigen::Vector3d(0, 1, 1.4));
  EXPECT_TRUE(T.linear().col(2).isApprox(Eigen::Vector3d::UnitX()));
  EXPECT_NEAR(T.linear().col(1).z(), 0.0, 1e-12);
  EXPECT_TRUE(T.linear().col(0).isApprox(Eigen::Vector3d::UnitZ()));  // x up, as a tag target on a side face
  EXPECT_NEAR(T.linear().determinant(), 1.0, 1e-12);
  EXPECT_TRUE(T.translation().isApprox(Eigen::Vector3d(1, 1, 0.8)));
  const Eigen::Isometry3d above = cloudTargetPose(Eigen::Vector3d(1, 1, 0.8), Eigen::Vector3d(1, 1, 1.4));
  EXPECT_NEAR(above.linear().determinant(), 1.0, 1e-12);
}

TEST(TargetSelector, ConfigLoadsEachKindAndRejectsMistakesNamingFileAndField) {
  auto load = [](const std::string& yaml) {
    const auto root = ConfigNode::loadString(yaml, "targets.yaml", "Test");
    return loadTargetSelector(root.child("target"));
  };
  EXPECT_EQ(load("target: {select: tag, tag_id: 3}").tag_id, 3);
  EXPECT_TRUE(load("target: {select: nearest, point: [1.7, 0.1, 0.8]}").point.isApprox(Eigen::Vector3d(1.7, 0.1, 0.8)));
  const TargetSelector k = load("target: {select: kth_from_front, k: 2, ambiguity: 0.01}");
  EXPECT_EQ(k.kind, TargetSelectorKind::KthFromFront);
  EXPECT_EQ(k.k, 2);
  EXPECT_EQ(k.summary(), "2nd from the front");
  std::string e = errorOf([&] { load("target: {select: biggest}"); });
  EXPECT_NE(e.find("targets.yaml"), std::string::npos) << e;
  EXPECT_NE(e.find("target.select"), std::string::npos) << e;
  EXPECT_NE(e.find("kth_from_left"), std::string::npos) << e;  // lists the known kinds
  e = errorOf([&] { load("target: {select: kth_from_left, k: 0}"); });
  EXPECT_NE(e.find("targets.yaml"), std::string::npos) << e;
  EXPECT_NE(e.find("target.k"), std::string::npos) << e;
  e = errorOf([&] { load("target: {select: nearest, point: [1, 2, 3], k: 2}"); });
  EXPECT_NE(e.find("target.k"), std::string::npos) << e;
  EXPECT_NE(e.find("not a field of a 'nearest' selector"), std::string::npos) << e;
  EXPECT_DOUBLE_EQ(load("target: {select: nearest, point: [1, 2, 3], radius: 0.1}").radius, 0.1);
  e = errorOf([&] { load("target: {select: nearest, point: [1, 2, 3], radius: -1}"); });
  EXPECT_NE(e.find("target.radius"), std::string::npos) << e;
  e = errorOf([&] { load("target: {select: nearest}"); });
  EXPECT_NE(e.find("target.point"), std::string::npos) << e;
  e = errorOf([&] { load("target: {select: nearest, point: [1, .nan, 3]}"); });
  EXPECT_NE(e.find("target.point"), std::string::npos) << e;
  e = errorOf([&] { load("target: {select: tag, tag_id: 1, ambiguity: 0}"); });
  EXPECT_NE(e.find("ambiguity"), std::string::npos) << e;
  EXPECT_NE(e.find("targets.yaml"), std::string::npos) << e;
}

}  // namespace
}  // namespace ehc_control
