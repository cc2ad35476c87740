#include "ehc_control/self_collision.h"

#include "ehc_common/config_node.h"
#include "ehc_control/fcl_geometry.h"

#include <fcl/geometry/shape/box.h>
#include <fcl/geometry/shape/cylinder.h>
#include <fcl/geometry/shape/sphere.h>
#include <fcl/narrowphase/collision.h>

#include <algorithm>
#include <random>
#include <set>

namespace ehc_control {

std::shared_ptr<fcl::CollisionGeometry<double>> makeFclGeometry(const CollisionShape& s) {
  std::shared_ptr<fcl::CollisionGeometry<double>> g;
  switch (s.type) {
    case CollisionShape::Type::Box:
      g = std::make_shared<fcl::Box<double>>(s.size.x(), s.size.y(), s.size.z());
      break;
    case CollisionShape::Type::Cylinder:
      g = std::make_shared<fcl::Cylinder<double>>(s.size[0], s.size[1]);
      break;
    case CollisionShape::Type::Sphere:
      g = std::make_shared<fcl::Sphere<double>>(s.size[0]);
      break;
  }
  g->computeLocalAABB();
  return g;
}

void SelfCollisionSampling::validate() const {
  ehc_common::requireRange("SelfCollisionSampling", "samples", samples, 1, 1e7);
}

namespace {
LinkPair ordered(const std::string& a, const std::string& b) { return a < b ? LinkPair{a, b} : LinkPair{b, a}; }
}  // namespace

std::vector<LinkPair> alwaysCollidingPairs(const WholeBodyModel& model, const RobotCollisionModel& collision,
                                           const SelfCollisionSampling& sampling) {
  sampling.validate();
  const auto& links = collision.links();
  const std::size_t n = links.size();
  std::vector<std::vector<std::shared_ptr<fcl::CollisionGeometry<double>>>> geoms(n);
  std::vector<int> index(n);
  for (std::size_t i = 0; i < n; ++i) {
    index[i] = model.linkIndex(links[i].name);
    for (const CollisionShape& s : links[i].shapes) geoms[i].push_back(makeFclGeometry(s));
  }
  // Candidates: every non-adjacent pair; a pair leaves as soon as one sample separates it.
  std::vector<std::pair<std::size_t, std::size_t>> candidates;
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i + 1; j < n; ++j)
      if (!collision.adjacent(links[i].name, links[j].name)) candidates.emplace_back(i, j);

  const RobotConfig& rc = model.config();
  std::mt19937 rng(sampling.seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  KinematicState state;
  std::vector<Eigen::Isometry3d> poses(n);
  fcl::CollisionRequest<double> request;
  for (int k = 0; k < sampling.samples && !candidates.empty(); ++k) {
    Eigen::VectorXd q(rc.nArm());
    for (int a = 0; a < rc.nArm(); ++a) q[a] = rc.arm_lower[a] + unit(rng) * (rc.arm_upper[a] - rc.arm_lower[a]);
    model.updateKinematics(Eigen::Vector3d::Zero(), q, &state);
    for (std::size_t i = 0; i < n; ++i) {
      const FingerJoint* f = collision.fingerOf(links[i].name);
      const double opening = f ? f->lower + unit(rng) * (f->upper - f->lower) : 0.0;
      poses[i] = state.linkPoseInBase(index[i]) * collision.fingerOffset(links[i].name, opening);
    }
    auto touching = [&](std::size_t i, std::size_t j) {
      for (std::size_t a = 0; a < geoms[i].size(); ++a)
        for (std::size_t b = 0; b < geoms[j].size(); ++b) {
          const fcl::CollisionObject<double> oa(geoms[i][a], poses[i] * links[i].shapes[a].origin);
          const fcl::CollisionObject<double> ob(geoms[j][b], poses[j] * links[j].shapes[b].origin);
          fcl::CollisionResult<double> result;
          if (fcl::collide(&oa, &ob, request, result) > 0) return true;
        }
      return false;
    };
    candidates.erase(std::remove_if(candidates.begin(), candidates.end(),
                                    [&](const auto& p) { return !touching(p.first, p.second); }),
                     candidates.end());
  }
  std::vector<LinkPair> out;
  for (const auto& [i, j] : candidates) out.push_back(ordered(links[i].name, links[j].name));
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<LinkPair> selfCollisionIgnorePairs(const WholeBodyModel& model, const RobotCollisionModel& collision,
                                               const SelfCollisionSampling& sampling) {
  std::set<LinkPair> out;
  const auto& links = collision.links();
  for (std::size_t i = 0; i < links.size(); ++i)
    for (std::size_t j = i + 1; j < links.size(); ++j)
      if (collision.adjacent(links[i].name, links[j].name)) out.insert(ordered(links[i].name, links[j].name));
  for (const LinkPair& p : alwaysCollidingPairs(model, collision, sampling)) out.insert(p);
  for (const auto& [a, b] : model.config().ignore_pairs) out.insert(ordered(a, b));
  return {out.begin(), out.end()};
}

}  // namespace ehc_control
