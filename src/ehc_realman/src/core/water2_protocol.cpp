#include "ehc_realman/water2_protocol.h"

#include <yaml-cpp/yaml.h>

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

std::string optionalString(const YAML::Node& map, const char* key) {
  const YAML::Node n = map[key];
  if (!n || n.IsNull()) return "";
  if (!n.IsScalar()) malformed(std::string("field '") + key + "' is not a string");
  return n.Scalar();
}

/// Strict RFC 8259 syntax check (yaml-cpp, used to read the fields, accepts more than JSON).
class JsonValidator {
 public:
  explicit JsonValidator(const std::string& s) : s_(s) {}
  bool valid() {
    ws();
    if (!value(0)) return false;
    ws();
    return i_ == s_.size();
  }

 private:
  void ws() {
    while (i_ < s_.size() && (s_[i_] == ' ' || s_[i_] == '\t' || s_[i_] == '\n' || s_[i_] == '\r')) ++i_;
  }
  bool lit(const char* word) {
    const std::size_t n = std::char_traits<char>::length(word);
    if (s_.compare(i_, n, word) != 0) return false;
    i_ += n;
    return true;
  }
  bool value(int depth) {
    if (depth > 64 || i_ >= s_.size()) return false;
    const char c = s_[i_];
    if (c == '{') return object(depth);
    if (c == '[') return array(depth);
    if (c == '"') return string();
    if (c == 't') return lit("true");
    if (c == 'f') return lit("false");
    if (c == 'n') return lit("null");
    return number();
  }
  bool object(int depth) {
    ++i_;
    ws();
    if (i_ < s_.size() && s_[i_] == '}') return ++i_, true;
    for (;;) {
      ws();
      if (i_ >= s_.size() || s_[i_] != '"' || !string()) return false;
      ws();
      if (i_ >= s_.size() || s_[i_] != ':') return false;
      ++i_;
      ws();
      if (!value(depth + 1)) return false;
      ws();
      if (i_ >= s_.size()) return false;
      if (s_[i_] == '}') return ++i_, true;
      if (s_[i_] != ',') return false;
      ++i_;
    }
  }
  bool array(int depth) {
    ++i_;
    ws();
    if (i_ < s_.size() && s_[i_] == ']') return ++i_, true;
    for (;;) {
      ws();
      if (!value(depth + 1)) return false;
      ws();
      if (i_ >= s_.size()) return false;
      if (s_[i_] == ']') return ++i_, true;
      if (s_[i_] != ',') return false;
      ++i_;
    }
  }
  bool string() {
    ++i_;  // opening quote
    while (i_ < s_.size()) {
      const unsigned char c = static_cast<unsigned char>(s_[i_++]);
      if (c == '"') return true;
      if (c < 0x20) return false;
      if (c == '\\') {
        if (i_ >= s_.size()) return false;
        const char e = s_[i_++];
        if (e == 'u') {
          for (int k = 0; k < 4; ++k, ++i_)
            if (i_ >= s_.size() || !std::isxdigit(static_cast<unsigned char>(s_[i_]))) return false;
        } else if (std::string("\"\\/bfnrt").find(e) == std::string::npos) {
          return false;
        }
      }
    }
    return false;
  }
  bool digits() {
    const std::size_t start = i_;
    while (i_ < s_.size() && std::isdigit(static_cast<unsigned char>(s_[i_]))) ++i_;
    return i_ > start;
  }
  bool number() {
    if (i_ < s_.size() && s_[i_] == '-') ++i_;
    if (i_ < s_.size() && s_[i_] == '0') ++i_;
    else if (!digits()) return false;
    if (i_ < s_.size() && s_[i_] == '.') {
      ++i_;
      if (!digits()) return false;
    }
    if (i_ < s_.size() && (s_[i_] == 'e' || s_[i_] == 'E')) {
      ++i_;
      if (i_ < s_.size() && (s_[i_] == '+' || s_[i_] == '-')) ++i_;
      if (!digits()) return false;
    }
    return true;
  }

  const std::string& s_;
  std::size_t i_ = 0;
};

double requireNumber(const YAML::Node& map, const char* key) {
  const YAML::Node n = map[key];
  if (!n || !n.IsScalar()) malformed(std::string("current_pose.") + key + " missing");
  double v = 0.0;
  try {
    v = n.as<double>();
  } catch (const YAML::Exception&) {
    malformed(std::string("current_pose.") + key + " is not a number");
  }
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
  if (!JsonValidator(json).valid()) malformed("invalid JSON syntax");
  YAML::Node root;
  try {
    root = YAML::Load(json);
  } catch (const YAML::Exception& e) {
    malformed(std::string("not JSON (") + e.what() + ")");
  }
  if (!root.IsMap()) malformed("not a JSON object");
  Water2Reply r;
  r.type = optionalString(root, "type");
  if (r.type.empty()) malformed("no 'type'");
  r.command = optionalString(root, "command");
  r.uuid = optionalString(root, "uuid");
  r.status = optionalString(root, "status");
  r.error_message = optionalString(root, "error_message");
  const YAML::Node results = root["results"];
  if (results && results.IsMap()) {
    const YAML::Node pose = results["current_pose"];
    if (pose) {
      if (!pose.IsMap()) malformed("current_pose is not an object");
      Water2Pose p;
      p.x = requireNumber(pose, "x");
      p.y = requireNumber(pose, "y");
      p.theta = requireNumber(pose, "theta");
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
  const auto quoted = [](const std::string& s) {
    std::string out = "\"";
    for (const char c : s) {
      if (c == '"' || c == '\\') out += '\\';
      if (static_cast<unsigned char>(c) >= 0x20) out += c;
    }
    return out + "\"";
  };
  std::string out = R"({"type":"response","command":)" + quoted(command) + R"(,"uuid":"","status":)" +
                    quoted(status) + R"(,"error_message":)" + quoted(error_message);
  if (pose) {
    char buf[192];
    std::snprintf(buf, sizeof(buf),
                  R"(,"results":{"move_status":"idle","charge_state":false,"power_percent":87,)"
                  R"("current_pose":{"x":%.6f,"y":%.6f,"theta":%.6f}})",
                  pose->x, pose->y, pose->theta);
    out += buf;
  }
  return out + "}";
}

}  // namespace ehc_realman
