#include "ehc_control/target_selector.h"

#include "ehc_common/config_node.h"
#include "ehc_common/enum_names.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace ehc_control {

namespace {

constexpr ehc_common::EnumNames<TargetSelectorKind, 4> kKindNames = {{
    {TargetSelectorKind::Tag, "tag"},
    {TargetSelectorKind::Nearest, "nearest"},
    {TargetSelectorKind::KthFromLeft, "kth_from_left"},
    {TargetSelectorKind::KthFromFront, "kth_from_front"},
}};

constexpr ehc_common::EnumNames<TargetSelectionStatus, 5> kStatusNames = {{
    {TargetSelectionStatus::Selected, "selected"},
    {TargetSelectionStatus::NoObject, "no_object"},
    {TargetSelectionStatus::TooFewObjects, "too_few_objects"},
    {TargetSelectionStatus::Ambiguous, "ambiguous"},
    {TargetSelectionStatus::NotCloudTarget, "not_cloud_target"},
}};

std::string ordinal(int k) {
  const int mod100 = k % 100;
  const char* suffix = (mod100 >= 11 && mod100 <= 13) ? "th" : k % 10 == 1 ? "st" : k % 10 == 2 ? "nd" : k % 10 == 3 ? "rd" : "th";
  return std::to_string(k) + suffix;
}

std::string fmt(double v) {
  std::ostringstream os;
  os.precision(3);
  os << v;
  return os.str();
}

std::string fmt(const Eigen::Vector3d& p) { return "(" + fmt(p.x()) + ", " + fmt(p.y()) + ", " + fmt(p.z()) + ")"; }

}  // namespace

std::string toString(TargetSelectorKind k) { return ehc_common::enumName(kKindNames, k, "TargetSelector"); }

TargetSelectorKind targetSelectorKindFromString(const std::string& s) {
  return ehc_common::enumValue(kKindNames, s, "TargetSelector", "selector kind");
}

std::string toString(TargetSelectionStatus s) { return ehc_common::enumName(kStatusNames, s, "TargetSelector"); }

void TargetSelector::validate() const {
  if (kind == TargetSelectorKind::Tag) ehc_common::requireRange("TargetSelector", "tag_id", tag_id, 0, 586);
  if (kind == TargetSelectorKind::Nearest && !point.allFinite())
    throw std::invalid_argument("[TargetSelector] parameter 'point' must be finite");
  if (kind == TargetSelectorKind::Nearest) ehc_common::requireRange("TargetSelector", "radius", radius, 0.0, 10.0);
  if (kind == TargetSelectorKind::KthFromLeft || kind == TargetSelectorKind::KthFromFront)
    ehc_common::requireRange("TargetSelector", "k", k, 1, 100);
  if (!(ambiguity > 0.0 && ambiguity <= 1.0))
    throw std::invalid_argument("[TargetSelector] parameter 'ambiguity' must be in (0, 1] m (is " + fmt(ambiguity) + ")");
}

std::string TargetSelector::summary() const {
  switch (kind) {
    case TargetSelectorKind::Tag: return "tag " + std::to_string(tag_id);
    case TargetSelectorKind::Nearest:
      return "nearest to " + fmt(point) + (radius > 0.0 ? " within " + fmt(radius) + " m" : std::string());
    case TargetSelectorKind::KthFromLeft: return ordinal(k) + " from the left";
    case TargetSelectorKind::KthFromFront: return ordinal(k) + " from the front";
  }
  return "";
}

TargetSelector loadTargetSelector(const ehc_common::ConfigNode& n) {
  TargetSelector s;
  const std::string kind = n.require<std::string>("select");
  try {
    s.kind = targetSelectorKindFromString(kind);
  } catch (const std::invalid_argument& e) {
    n.fail("select", std::string("is not a selector kind: ") + e.what());
  }
  // Only the fields of the kind: a `k` on a nearest selector is a mistake, not ignored.
  const bool kth = s.kind == TargetSelectorKind::KthFromLeft || s.kind == TargetSelectorKind::KthFromFront;
  const auto only = [&](const char* key, bool allowed) {
    if (n.has(key) && !allowed) n.fail(key, "is not a field of a '" + kind + "' selector");
  };
  only("tag_id", s.kind == TargetSelectorKind::Tag);
  only("point", s.kind == TargetSelectorKind::Nearest);
  only("radius", s.kind == TargetSelectorKind::Nearest);
  only("k", kth);
  if (s.kind == TargetSelectorKind::Tag) s.tag_id = n.getInRange("tag_id", s.tag_id, 0, 586);
  if (s.kind == TargetSelectorKind::Nearest) {
    s.point = n.requireVector("point", 3);
    s.radius = n.getInRange("radius", s.radius, 0.0, 10.0);
  }
  if (kth) s.k = n.getInRange("k", s.k, 1, 100);
  s.ambiguity = n.get("ambiguity", s.ambiguity);
  n.validate(s);
  return s;
}

TargetSelection selectTarget(const TargetSelector& selector, const std::vector<Eigen::Vector3d>& centres,
                             const Eigen::Isometry3d& camera, const Eigen::Vector3d& up) {
  TargetSelection out;
  if (!selector.fromCloud()) {
    out.status = TargetSelectionStatus::NotCloudTarget;
    out.detail = selector.summary() + ": a tag target comes from the tag detector";
    return out;
  }
  // The ranked quantity per object, smallest first.
  const Eigen::Vector3d u = up.normalized();
  Eigen::Vector3d front = camera.linear().col(2) - camera.linear().col(2).dot(u) * u;
  if (front.norm() < 1e-6) front = -camera.linear().col(1) + camera.linear().col(1).dot(u) * u;  // straight down: image up
  front.normalize();
  const Eigen::Vector3d left = u.cross(front);
  std::vector<std::pair<double, int>> ranked;
  for (std::size_t i = 0; i < centres.size(); ++i) {
    const Eigen::Vector3d& c = centres[i];
    if (!c.allFinite()) continue;
    if (selector.kind == TargetSelectorKind::Nearest && selector.radius > 0.0 && (c - selector.point).norm() > selector.radius)
      continue;
    double key = 0.0;
    switch (selector.kind) {
      case TargetSelectorKind::Nearest: key = (c - selector.point).norm(); break;
      case TargetSelectorKind::KthFromLeft: key = -(c - camera.translation()).dot(left); break;
      case TargetSelectorKind::KthFromFront: key = (c - camera.translation()).dot(front); break;
      case TargetSelectorKind::Tag: break;
    }
    ranked.emplace_back(key, static_cast<int>(i));
  }
  std::sort(ranked.begin(), ranked.end());
  const std::size_t want = selector.kind == TargetSelectorKind::Nearest ? 0 : static_cast<std::size_t>(selector.k - 1);
  if (ranked.empty()) {
    out.status = TargetSelectionStatus::NoObject;
    out.detail = selector.summary() + ": no object in the view" +
                 (selector.kind == TargetSelectorKind::Nearest && selector.radius > 0.0 ? " within the radius" : "");
    return out;
  }
  if (want >= ranked.size()) {
    out.status = TargetSelectionStatus::TooFewObjects;
    out.detail = selector.summary() + ": only " + std::to_string(ranked.size()) + " object(s) in the view";
    return out;
  }
  for (const std::size_t other : {want - 1, want + 1}) {  // want - 1 wraps for want 0: skipped
    if (other >= ranked.size()) continue;
    const double gap = std::abs(ranked[other].first - ranked[want].first);
    if (gap < selector.ambiguity) {
      out.status = TargetSelectionStatus::Ambiguous;
      out.detail = selector.summary() + ": ambiguous, the objects at " + fmt(centres[ranked[want].second]) + " and " +
                   fmt(centres[ranked[other].second]) + " differ by " + fmt(gap) + " m (< " + fmt(selector.ambiguity) + " m)";
      return out;
    }
  }
  out.status = TargetSelectionStatus::Selected;
  out.index = ranked[want].second;
  out.centre = centres[static_cast<std::size_t>(out.index)];
  out.detail = selector.summary() + ": the object at " + fmt(out.centre) + " (" + std::to_string(ranked.size()) +
               " in the view)";
  return out;
}

Eigen::Isometry3d cloudTargetPose(const Eigen::Vector3d& centre, const Eigen::Vector3d& viewpoint, const Eigen::Vector3d& up) {
  const Eigen::Vector3d u = up.normalized();
  Eigen::Vector3d z = centre - viewpoint;
  z -= z.dot(u) * u;
  if (!(z.norm() > 1e-6)) z = Eigen::Vector3d::UnitX() - Eigen::Vector3d::UnitX().dot(u) * u;
  z.normalize();
  const Eigen::Vector3d y = z.cross(u).normalized();
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear().col(0) = y.cross(z);
  T.linear().col(1) = y;
  T.linear().col(2) = z;
  T.translation() = centre;
  return T;
}

}  // namespace ehc_control
