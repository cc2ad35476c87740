#pragma once
// TargetSelector <-> ehc_msgs/TargetSelector: the one home of this conversion for the nodes (the
// grasp sequencer takes a selector per object and sends the current object's; the grasp node
// selects by it). Node side only (message headers), beside camera_info_msg.h. Header-only.

#include "ehc_control/target_selector.h"
#include "ehc_msgs/TargetSelector.h"

#include <stdexcept>
#include <string>

namespace ehc_control {

/// The selector of a message, validated. Throws std::invalid_argument "[TargetSelector] ..." for
/// an unknown kind or a value out of range; a zero ambiguity means the default.
inline TargetSelector selectorFromMsg(const ehc_msgs::TargetSelector& m) {
  TargetSelector s;
  s.kind = targetSelectorKindFromString(m.select);
  s.tag_id = m.tag_id;
  s.point = Eigen::Vector3d(m.point.x, m.point.y, m.point.z);
  s.radius = m.radius;
  s.k = m.k;
  if (m.ambiguity != 0.0) s.ambiguity = m.ambiguity;
  s.validate();
  return s;
}

inline ehc_msgs::TargetSelector selectorToMsg(const TargetSelector& s, const std::string& object,
                                              const std::string& frame, const ros::Time& stamp) {
  ehc_msgs::TargetSelector m;
  m.header.frame_id = frame;
  m.header.stamp = stamp;
  m.object = object;
  m.select = toString(s.kind);
  m.tag_id = s.tag_id;
  m.point.x = s.point.x();
  m.point.y = s.point.y();
  m.point.z = s.point.z();
  m.radius = s.radius;
  m.k = s.k;
  m.ambiguity = s.ambiguity;
  return m;
}

}  // namespace ehc_control
