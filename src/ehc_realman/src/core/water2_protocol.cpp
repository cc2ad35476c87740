#include "ehc_realman/water2_protocol.h"

#include "ehc_common/json.h"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

namespace ehc_realman {

namespace {
[[noreturn]] void malformed(const std::string& what) {
  throw std::runtime_error("[Water2Protocol] malformed reply: " + what);
}

/// A string field; missing or null reads as "", a number or boolean as its JSON text.
std::string optionalString(const ehc_common::Json& map, const char* key) {
  const auto it = map.find(key);
  if (it == map.end() || it->is_null()) return "";
  if (it->is_string()) return it->get<std::string>();
  if (it->is_structured()) malformed(std::string("field '") + key + "' is not a string");
  return it->dump();
}

double requireNumber(const ehc_common::Json& map, const char* key) {
  const auto it = map.find(key);
  if (it == map.end()) malformed(std::string("current_pose.") + key + " missing");
  if (!it->is_number()) malformed(std::string("current_pose.") + key + " is not a number");
  const double v = it->get<double>();
  if (!std::isfinite(v)) malformed(std::string("current_pose.") + key + " is not finite");
  return v;
}
}  // namespace

std::string joyControlRequest(double linear_velocity, double angular_velocity) {
  if (!std::isfinite(linear_velocity) || !std::isfinite(angular_velocity))
    throw std::invalid_argument("[Water2Protocol] joy_control velocities must be finite");
  char buf[128];
  std::snprintf(buf, sizeof(buf), "/api/joy_control?angular_velocity=%.4f&linear_velocity=%.4f",
                angular_velocity + 0.0, linear_velocity + 0.0);  // + 0.0: no "-0.0000"
  return buf;
}

std::string robotStatusRequest() { return "/api/robot_status"; }

Water2Reply parseWater2Reply(const std::string& json) {
  ehc_common::Json root;
  try {
    root = ehc_common::Json::parse(json);  // strict RFC 8259
  } catch (const ehc_common::Json::exception& e) {  // syntax, or a number out of range (1e999)
    malformed(std::string("invalid JSON (") + e.what() + ")");
  }
  if (!root.is_object()) malformed("not a JSON object");
  Water2Reply r;
  r.type = optionalString(root, "type");
  if (r.type.empty()) malformed("no 'type'");
  r.command = optionalString(root, "command");
  r.uuid = optionalString(root, "uuid");
  r.status = optionalString(root, "status");
  r.error_message = optionalString(root, "error_message");
  const auto results = root.find("results");
  if (results != root.end() && results->is_object()) {
    const auto pose = results->find("current_pose");
    if (pose != results->end()) {
      if (!pose->is_object()) malformed("current_pose is not an object");
      Water2Pose p;
      p.x = requireNumber(*pose, "x");
      p.y = requireNumber(*pose, "y");
      p.theta = requireNumber(*pose, "theta");
      r.pose = p;
    }
  }
  return r;
}

JsonObjectSplitter::JsonObjectSplitter(std::size_t max_object_bytes)
    : max_object_bytes_(max_object_bytes) {}

void JsonObjectSplitter::clear() {
  current_.clear();
  depth_ = 0;
  in_string_ = escape_ = skipping_ = false;
  ready_.clear();
}

void JsonObjectSplitter::feed(const char* data, std::size_t size) {
  for (std::size_t i = 0; i < size; ++i) {
    const char c = data[i];
    if (depth_ == 0) {
      if (c == '{') {
        depth_ = 1;
        in_string_ = escape_ = false;
        skipping_ = false;
        current_.assign(1, c);
      } else if (!std::isspace(static_cast<unsigned char>(c))) {
        ++dropped_bytes_;
      }
      continue;
    }
    if (!skipping_) current_ += c;
    if (in_string_) {
      if (escape_) escape_ = false;
      else if (c == '\\') escape_ = true;
      else if (c == '"') in_string_ = false;
    } else if (c == '"') {
      in_string_ = true;
    } else if (c == '{') {
      ++depth_;
    } else if (c == '}') {
      if (--depth_ == 0) {
        if (!skipping_) ready_.push_back(std::move(current_));
        current_.clear();
        skipping_ = false;
        continue;
      }
    }
    if (!skipping_ && current_.size() > max_object_bytes_) {
      ++overflows_;
      dropped_bytes_ += current_.size();
      current_.clear();
      current_.shrink_to_fit();
      skipping_ = true;  // drop the rest of this object
    } else if (skipping_) {
      ++dropped_bytes_;
    }
  }
  // Bound the queue too: a flood of objects nobody reads must not grow without limit.
  while (ready_.size() > 1024) {
    dropped_bytes_ += ready_.front().size();
    ready_.pop_front();
  }
}

bool JsonObjectSplitter::next(std::string& object) {
  if (ready_.empty()) return false;
  object = std::move(ready_.front());
  ready_.pop_front();
  return true;
}

// ---------------------------------------------------------------- the base's side
Water2Request parseWater2Request(const std::string& text) {
  Water2Request r;
  r.text = text;
  while (!r.text.empty() && std::isspace(static_cast<unsigned char>(r.text.back()))) r.text.pop_back();
  r.command = r.text.substr(0, r.text.find('?'));
  if (r.command == "/api/joy_control") {
    double w = NAN, v = NAN;
    char tail = 0;
    if (std::sscanf(r.text.c_str(), "/api/joy_control?angular_velocity=%lf&linear_velocity=%lf%c", &w, &v,
                    &tail) == 2 &&
        std::isfinite(w) && std::isfinite(v)) {
      r.joy = true;
      r.linear = v;
      r.angular = w;
    }
  }
  return r;
}

namespace {
/// A complete request without a terminator: its full fixed format.
bool completeWithoutTerminator(const std::string& r) {
  if (r == "/api/robot_status") return true;
  double w = 0.0, v = 0.0;
  int end = 0;
  if (std::sscanf(r.c_str(), "/api/joy_control?angular_velocity=%lf&linear_velocity=%lf%n", &w, &v, &end) != 2)
    return false;
  const auto decimals = [&](std::size_t from) {  // 4 decimals after the last '.' before `from`
    const std::size_t dot = r.rfind('.', from);
    return dot != std::string::npos && from - dot == 5;
  };
  return static_cast<std::size_t>(end) == r.size() && decimals(r.size()) && decimals(r.find('&'));
}
}  // namespace

void Water2RequestSplitter::feed(const char* data, std::size_t size) {
  buffer_.append(data, size);
  split();
  if (buffer_.size() > max_request_bytes_) buffer_.clear();  // no request is that long
}

void Water2RequestSplitter::split() {
  for (;;) {
    const auto start = buffer_.find("/api/");
    if (start == std::string::npos) {
      // Keep a possible beginning of "/api/" at the end.
      buffer_.erase(0, buffer_.size() > 4 ? buffer_.size() - 4 : 0);
      return;
    }
    const auto next = buffer_.find("/api/", start + 5);
    std::string r = buffer_.substr(start, next == std::string::npos ? std::string::npos : next - start);
    if (next == std::string::npos) {
      std::string trimmed = r;
      while (!trimmed.empty() && std::isspace(static_cast<unsigned char>(trimmed.back()))) trimmed.pop_back();
      if (!completeWithoutTerminator(trimmed) && (r.empty() || r.back() != '\n')) {
        buffer_.erase(0, start);
        return;
      }
      buffer_.clear();
    } else {
      buffer_.erase(0, next);
    }
    while (!r.empty() && std::isspace(static_cast<unsigned char>(r.back()))) r.pop_back();
    ready_.push_back(r);
  }
}

bool Water2RequestSplitter::next(std::string& request) {
  if (ready_.empty()) return false;
  request = std::move(ready_.front());
  ready_.pop_front();
  return true;
}

std::string water2ResponseJson(const std::string& command, const std::string& status,
                               const std::string& error_message, const std::optional<Water2Pose>& pose) {
  ehc_common::Json j;
  j["type"] = "response";
  j["command"] = command;
  j["uuid"] = "";
  j["status"] = status;
  j["error_message"] = error_message;
  if (pose) {
    ehc_common::Json& results = j["results"];
    results["move_status"] = "idle";
    results["charge_state"] = false;
    results["power_percent"] = 87;
    results["current_pose"] = {{"x", ehc_common::jsonNumber(pose->x)},
                               {"y", ehc_common::jsonNumber(pose->y)},
                               {"theta", ehc_common::jsonNumber(pose->theta)}};
  }
  return ehc_common::jsonLine(j);
}

}  // namespace ehc_realman
