#pragma once
// initNode: ros::init and the node's private parameters, the same way in every node.
//   - An invalid command-line argument (e.g. a pasted `[_mode:=ehc|neo_e]`, which the shell cuts
//     into `[_mode:=ehc`) is an error naming it, not an abort (ros::init throws
//     ros::InvalidNameException).
//   - The private namespace is read once into ehc_common::NodeParams (typed, strict reads).
//   - A private parameter given on this command line (`_name:=value`) applies to this run only:
//     it is removed from the parameter server as soon as it is read, so a later `rosrun` without
//     it gets the configuration file's value, even if this run was killed. Parameters set by a
//     launch file or `rosparam set` stay (ROS convention); checkNodeParams logs where each came from.
// Header-only (roscpp).

#include "ehc_common/node_params.h"

#include <ros/ros.h>
#include <xmlrpcpp/XmlRpcValue.h>

#include <map>
#include <stdexcept>
#include <string>

namespace ehc_common {

inline ParamValue paramValueFromXmlRpc(XmlRpc::XmlRpcValue& v) {
  switch (v.getType()) {
    case XmlRpc::XmlRpcValue::TypeBoolean: return ParamValue::ofBool(static_cast<bool>(v));
    case XmlRpc::XmlRpcValue::TypeInt: return ParamValue::ofInt(static_cast<int>(v));
    case XmlRpc::XmlRpcValue::TypeDouble: return ParamValue::ofDouble(static_cast<double>(v));
    case XmlRpc::XmlRpcValue::TypeString: return ParamValue::ofString(static_cast<std::string>(v));
    case XmlRpc::XmlRpcValue::TypeArray: {
      ParamValue p;
      p.kind = ParamValue::Kind::List;
      for (int i = 0; i < v.size(); ++i) p.items.push_back(paramValueFromXmlRpc(v[i]));
      return p;
    }
    case XmlRpc::XmlRpcValue::TypeStruct: {
      ParamValue p;
      p.kind = ParamValue::Kind::Map;
      return p;
    }
    default: return ParamValue::ofString(v.toXml());
  }
}

/// ros::init(argc, argv, name), then the private parameters. Throws std::invalid_argument
/// "[name] invalid command-line argument ..." when ros::init rejects an argument.
inline NodeParams initNode(int& argc, char** argv, const std::string& name, uint32_t options = 0) {
  const std::set<std::string> given = commandLineParamNames(argc, argv);
  try {
    ros::init(argc, argv, name, options);
  } catch (const ros::Exception& e) {
    throw std::invalid_argument(std::string("invalid command-line argument: ") + e.what() +
                                " (remap a topic with name:=new_name, set a private parameter with _name:=value)");
  }
  std::map<std::string, ParamValue> values;
  XmlRpc::XmlRpcValue all;
  if (ros::param::get("~", all) && all.getType() == XmlRpc::XmlRpcValue::TypeStruct)
    for (auto& kv : all) values[kv.first] = paramValueFromXmlRpc(kv.second);
  for (const std::string& n : given) ros::param::del("~" + n);  // this run's only
  return NodeParams(ros::this_node::getName(), std::move(values), given);
}

/// After the node has read its parameters: a command-line parameter no reader asked for is an
/// error (NodeParams::rejectUnknown); one only on the server is a warning; the values read and
/// their sources are logged once.
inline void checkNodeParams(const NodeParams& params) {
  params.rejectUnknown();
  for (const std::string& n : params.unread())
    ROS_WARN_STREAM("[" << params.node() << "] private parameter _" << n
                        << " is set on the parameter server but not read by this node");
  ROS_INFO_STREAM("[" << params.node() << "] private parameters: " << params.summary());
}

/// A node's main: initNode, one NodeHandle, `body(params, nh)` (returns the exit code). An
/// exception (a bad argument, parameter or configuration) is logged as one FATAL line
/// "[name] <what>" and exits with `error_code`. The NodeHandle lives until the message is out:
/// destroying the last one shuts roscpp down, its logging included (a message logged after it
/// was lost).
template <class Body>
int runNode(int& argc, char** argv, const std::string& name, int error_code, Body&& body) {
  NodeParams params;
  try {
    params = initNode(argc, argv, name);
  } catch (const std::exception& e) {
    ROS_FATAL_STREAM("[" << name << "] " << e.what());
    return error_code;
  }
  ros::NodeHandle nh;
  try {
    return body(static_cast<const NodeParams&>(params), nh);
  } catch (const std::exception& e) {
    ROS_FATAL_STREAM("[" << name << "] " << e.what());
    return error_code;
  }
}

}  // namespace ehc_common
