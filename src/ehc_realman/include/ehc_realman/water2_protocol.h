#pragma once
// Water2 base TCP API (vendor chassis API, port 31001): requests are plain text command lines
// ("/api/joy_control?angular_velocity=W&linear_velocity=V", "/api/robot_status"), replies are
// JSON objects {"type": "response", "command": ..., "uuid": ..., "status": "OK",
// "error_message": ..., "results": {... "current_pose": {"x", "y", "theta"} ...}}, sent back to
// back on the stream. ROS-free: formatting, stream splitting and reply parsing only.

#include <cstddef>
#include <cstdint>
#include <deque>
#include <optional>
#include <string>

namespace ehc_realman {

/// Base pose in the Water2 map frame: m, m, rad.
struct Water2Pose {
  double x = 0.0;
  double y = 0.0;
  double theta = 0.0;
};

struct Water2Reply {
  std::string type;     ///< "response", "callback" or "notification"
  std::string command;  ///< e.g. "/api/robot_status" (may be empty for notifications)
  std::string uuid;
  std::string status;   ///< "OK" on success
  std::string error_message;
  std::optional<Water2Pose> pose;  ///< results.current_pose when present
  bool ok() const { return status == "OK"; }
};

/// "/api/joy_control?angular_velocity=W&linear_velocity=V" (4 decimals).
/// Throws std::invalid_argument "[Water2Protocol] ..." on non-finite values.
std::string joyControlRequest(double linear_velocity, double angular_velocity);
/// "/api/robot_status".
std::string robotStatusRequest();

/// Parses one JSON reply object. Throws std::runtime_error "[Water2Protocol] ..." when the text
/// is not a JSON object, lacks a string "type", or carries a malformed current_pose.
Water2Reply parseWater2Reply(const std::string& json);

// ---------------------------------------------------------------- the base's side (stand-ins)
// What the Water2 itself does with the stream: used by the hardware stand-in of the deployment
// rehearsal (ehc_sim::Water2ApiServer) and the tests' fake server, so both speak exactly the
// protocol the bridge's client side above formats and parses.

/// One request as the base receives it.
struct Water2Request {
  std::string text;     ///< the whole request, trailing blanks removed
  std::string command;  ///< the path before '?', e.g. "/api/joy_control"
  bool joy = false;     ///< a well-formed joy_control (both velocities parsed and finite)
  double linear = 0.0;  ///< m/s (joy only)
  double angular = 0.0; ///< rad/s (joy only)
};
/// Never throws: an unknown or malformed request keeps joy = false.
Water2Request parseWater2Request(const std::string& text);

/// Cuts the request stream into requests. The vendor protocol has no terminator: a request
/// starts with "/api/" and is complete when the next one starts, when it ends with a newline,
/// or when it already matches its full fixed format (joy_control with two 4-decimal values,
/// robot_status). Bytes before "/api/" are dropped. Memory stays bounded (max_request_bytes).
class Water2RequestSplitter {
 public:
  explicit Water2RequestSplitter(std::size_t max_request_bytes = 4096)
      : max_request_bytes_(max_request_bytes) {}
  void feed(const char* data, std::size_t size);
  /// Pops the next complete request; false if none is complete yet.
  bool next(std::string& request);
  void clear() { buffer_.clear(); ready_.clear(); }

 private:
  void split();
  std::size_t max_request_bytes_;
  std::string buffer_;
  std::deque<std::string> ready_;
};

/// The base's JSON reply to `command`: {"type":"response","command":..,"uuid":"","status":..,
/// "error_message":..[,"results":{.."current_pose":{x,y,theta}}]}; results only with a pose.
std::string water2ResponseJson(const std::string& command, const std::string& status,
                               const std::string& error_message,
                               const std::optional<Water2Pose>& pose = std::nullopt);

/// Cuts a byte stream into top-level JSON objects ({...}, strings and escapes respected).
/// Bytes outside objects are dropped (non-blank ones are counted); an object longer than
/// max_object_bytes is dropped whole (counted as an overflow). Memory stays bounded.
class JsonObjectSplitter {
 public:
  explicit JsonObjectSplitter(std::size_t max_object_bytes = 65536);
  void feed(const char* data, std::size_t size);
  void feed(const std::string& data) { feed(data.data(), data.size()); }
  /// Pops the next complete object; false if none is complete yet.
  bool next(std::string& object);
  void clear();
  std::uint64_t droppedBytes() const { return dropped_bytes_; }
  std::uint64_t overflows() const { return overflows_; }

 private:
  std::size_t max_object_bytes_;
  std::string current_;
  int depth_ = 0;
  bool in_string_ = false;
  bool escape_ = false;
  bool skipping_ = false;  ///< inside an oversized object: drop until it closes
  std::deque<std::string> ready_;
  std::uint64_t dropped_bytes_ = 0;
  std::uint64_t overflows_ = 0;
};

}  // namespace ehc_realman
