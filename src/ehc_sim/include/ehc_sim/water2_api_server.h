#pragma once
// Water2ApiServer: the Water2 chassis API served on 127.0.0.1 by the hardware stand-in
// (ehc_hardware_standin_node), so the real water2_base_bridge connects to it exactly as to the
// base: requests as the vendor sends them (ehc_realman::Water2RequestSplitter,
// parseWater2Request), replies in the base's JSON (ehc_realman::water2ResponseJson). One client
// at a time (a new connection replaces the old one, as the bridge reconnects). Single-threaded:
// the caller serves it from its own loop (serve()), so nothing runs behind its back.
// ROS-free, POSIX sockets; loopback only.

#include "ehc_realman/water2_protocol.h"

#include <functional>
#include <string>

namespace ehc_sim {

struct Water2ApiCounters {
  long connections = 0;
  long joy_controls = 0;     ///< well-formed joy_control requests
  long status_requests = 0;  ///< robot_status requests answered
  long bad_requests = 0;     ///< unknown or malformed requests (answered with an error status)
};

class Water2ApiServer {
 public:
  /// What the base does with a joy_control (m/s, rad/s) and what robot_status reports.
  using JoyHandler = std::function<void(double linear, double angular)>;
  using PoseSource = std::function<ehc_realman::Water2Pose()>;

  /// Listens on 127.0.0.1:`port` (0: an ephemeral port, see port()). Throws
  /// std::runtime_error "[Water2ApiServer] ..." if it cannot.
  explicit Water2ApiServer(int port);
  ~Water2ApiServer();
  Water2ApiServer(const Water2ApiServer&) = delete;
  Water2ApiServer& operator=(const Water2ApiServer&) = delete;

  int port() const { return port_; }
  bool clientConnected() const { return client_fd_ >= 0; }

  /// Waits at most `timeout_s` for a connection or data, then accepts, reads what has arrived
  /// and answers every complete request: joy_control -> on_joy, then an OK reply; robot_status
  /// -> an OK reply with status_pose(); anything else -> an error reply. A client that hangs up
  /// or fails is dropped (the bridge reconnects). Never throws on network errors.
  void serve(double timeout_s, const JoyHandler& on_joy, const PoseSource& status_pose);

  const Water2ApiCounters& counters() const { return counters_; }

 private:
  void closeClient();
  void send(const std::string& text);

  int port_ = 0;
  int listen_fd_ = -1;
  int client_fd_ = -1;
  ehc_realman::Water2RequestSplitter splitter_;
  Water2ApiCounters counters_;
};

}  // namespace ehc_sim
