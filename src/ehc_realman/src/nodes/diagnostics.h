#pragma once
// Diagnostics of the RealMan adapter nodes (rm_arm_adapter, water2_base_bridge): the key-value
// pairs of their diagnostic_msgs/DiagnosticStatus.

#include <diagnostic_msgs/KeyValue.h>

#include <string>

namespace ehc_realman_nodes {

/// One key-value pair of a DiagnosticStatus.
inline diagnostic_msgs::KeyValue kv(const std::string& key, const std::string& value) {
  diagnostic_msgs::KeyValue k;
  k.key = key;
  k.value = value;
  return k;
}

}  // namespace ehc_realman_nodes
