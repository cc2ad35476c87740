#pragma once
// FakeWater2Server (tests only): a Water2 chassis API stand-in on 127.0.0.1 (loopback only).
// Records every request with its arrival time, simulates the base (unicycle driven by the last
// joy_control, each command lasting 0.5 s as on the real base), answers robot_status with the
// simulated pose, and can misbehave on request (garbage, truncated, invalid JSON, missing fields,
// bad pose, oversized, error status, silence). stop() closes everything ("killed"); start()
// listens again on the same port. Its clock (request times, the simulated base) is the steady
// clock by default, or the lock-step test's (constructor); handled() counts the requests it has
// answered (or, misbehaving, withheld the answer to), for a lock-step test's handshake.

#include "wall_clock.h"

#include "ehc_realman/water2_client.h"
#include "ehc_realman/water2_protocol.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace ehc_realman_test {

class FakeWater2Server {
 public:
  struct Request {
    double time = 0.0;  ///< the server's clock at arrival, s
    std::string text;
    bool joy = false;
    double linear = 0.0, angular = 0.0;
    int connection = 0;  ///< 1 for the first accepted connection, 2 for the next, ...
  };
  enum class ReplyMode { Normal, Garbage, Truncated, BadJson, MissingType, BadPose, Oversized,
                         ErrorStatus, Silent };

  using Clock = std::function<double()>;
  static double now() { return ehc_realman_test::now(); }

  /// port 0: an ephemeral port is chosen by the first start(). `clock`: the steady clock if empty.
  explicit FakeWater2Server(int port = 0, Clock clock = Clock())
      : port_(port), clock_(clock ? std::move(clock) : Clock(&FakeWater2Server::now)) {}
  ~FakeWater2Server() { stop(); }

  void start() {
    stop();
    listen_fd_ = ehc_realman::listenOnLoopback(&port_, /*nonblocking=*/false, "FakeWater2Server");
    running_ = true;
    thread_ = std::thread([this] { loop(); });
  }

  /// Closes the listening socket and the client connection ("kill").
  void stop() {
    running_ = false;
    if (thread_.joinable()) thread_.join();
    if (client_fd_ >= 0) ::close(client_fd_);
    if (listen_fd_ >= 0) ::close(listen_fd_);
    client_fd_ = listen_fd_ = -1;
  }

  int port() const { return port_; }
  bool running() const { return running_; }
  void setReplyMode(ReplyMode m) { mode_ = m; }
  int connections() const { return connections_; }
  std::uint64_t handled() const { return handled_; }
  /// Replies are held back while `hold` (a reply in flight, read late by the client); on
  /// release the server thread sends them in one go and counts releases().
  void holdReplies(bool hold) {
    if (!hold) release_requested_ = true;
    hold_ = hold;
  }
  std::uint64_t releases() const { return releases_; }
  std::vector<Request> requests() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return requests_;
  }
  void clearRequests() {
    std::lock_guard<std::mutex> lock(mutex_);
    requests_.clear();
  }
  void pose(double& x, double& y, double& theta) const {
    std::lock_guard<std::mutex> lock(mutex_);
    x = x_;
    y = y_;
    theta = theta_;
  }
  void setPose(double x, double y, double theta) {
    std::lock_guard<std::mutex> lock(mutex_);
    x_ = x;
    y_ = y;
    theta_ = theta;
  }

 private:
  void loop() {
    double last = clock_();
    while (running_) {
      pollfd fds[2] = {{listen_fd_, POLLIN, 0}, {client_fd_, POLLIN, 0}};
      ::poll(fds, client_fd_ >= 0 ? 2 : 1, 5);
      const double t = clock_();
      simulate(t - last, t);
      last = t;
      if (fds[0].revents & POLLIN) {
        const int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC);
        if (fd >= 0) {
          if (client_fd_ >= 0) ::close(client_fd_);
          client_fd_ = fd;
          ++connections_;
          splitter_.clear();
        }
      }
      if (client_fd_ >= 0 && (fds[1].revents & (POLLIN | POLLHUP | POLLERR))) {
        char buf[4096];
        const ssize_t n = ::recv(client_fd_, buf, sizeof(buf), MSG_DONTWAIT);
        if (n <= 0) {
          ::close(client_fd_);
          client_fd_ = -1;
          continue;
        }
        splitter_.feed(buf, static_cast<std::size_t>(n));
        std::string r;
        while (splitter_.next(r)) handle(r, t);
      }
      if (!hold_ && release_requested_.exchange(false)) {
        sendAll(held_out_);
        held_out_.clear();
        ++releases_;
      }
    }
  }

  void simulate(double dt, double t) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (t - joy_time_ > 0.5 || dt <= 0.0) return;
    x_ += joy_v_ * dt * std::cos(theta_);
    y_ += joy_v_ * dt * std::sin(theta_);
    theta_ = std::atan2(std::sin(theta_ + joy_w_ * dt), std::cos(theta_ + joy_w_ * dt));
  }

  void handle(const std::string& text, double t) {
    const ehc_realman::Water2Request parsed = ehc_realman::parseWater2Request(text);
    Request r;
    r.time = t;
    r.text = parsed.text;
    r.connection = connections_;
    r.joy = parsed.joy;
    r.linear = parsed.linear;
    r.angular = parsed.angular;
    const std::string& command = parsed.command;
    ehc_realman::Water2Pose pose;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      requests_.push_back(r);
      if (r.joy) {
        joy_v_ = r.linear;
        joy_w_ = r.angular;
        joy_time_ = t;
      }
      pose = ehc_realman::Water2Pose{x_, y_, theta_};
    }
    reply(command, pose);
    ++handled_;
  }

  void reply(const std::string& command, const ehc_realman::Water2Pose& pose) {
    std::string out;
    const std::string head = R"({"type":"response","command":")" + command + R"(","uuid":"",)";
    switch (mode_.load()) {
      case ReplyMode::Normal:
        out = ehc_realman::water2ResponseJson(
            command, "OK", "", command == "/api/robot_status" ? std::optional<ehc_realman::Water2Pose>(pose)
                                                              : std::nullopt);
        break;
      case ReplyMode::Garbage: out = "HTTP/1.1 500 oops\r\n\r\n<html>not json</html>\n"; break;
      case ReplyMode::Truncated: out = head + R"("status":"O)"; break;
      case ReplyMode::BadJson: out = R"({"type":"response","command": ,,})"; break;
      case ReplyMode::MissingType: out = R"({"command":")" + command + R"(","status":"OK"})"; break;
      case ReplyMode::BadPose:
        out = head + R"("status":"OK","error_message":"","results":{"current_pose":)"
                     R"({"x":"abc","y":1,"theta":null}}})";
        break;
      case ReplyMode::Oversized:
        out = head + R"("status":"OK","error_message":")" + std::string(100000, 'x') + R"("})";
        break;
      case ReplyMode::ErrorStatus:
        out = head + R"("status":"ESTOP_ACTIVE","error_message":"emergency stop pressed"})";
        break;
      case ReplyMode::Silent: return;
    }
    if (hold_) {
      held_out_ += out;
      return;
    }
    sendAll(out);
  }

  void sendAll(const std::string& out) {
    std::size_t done = 0;
    while (done < out.size() && client_fd_ >= 0) {
      const ssize_t n = ::send(client_fd_, out.data() + done, out.size() - done, MSG_NOSIGNAL);
      if (n <= 0) break;
      done += static_cast<std::size_t>(n);
    }
  }

  int port_;
  Clock clock_;
  std::atomic<std::uint64_t> handled_{0};
  int listen_fd_ = -1;
  int client_fd_ = -1;
  std::atomic<bool> running_{false};
  std::atomic<ReplyMode> mode_{ReplyMode::Normal};
  std::atomic<bool> hold_{false};
  std::atomic<bool> release_requested_{false};
  std::atomic<std::uint64_t> releases_{0};
  std::string held_out_;  ///< replies held back (server thread only)
  std::atomic<int> connections_{0};
  std::thread thread_;
  ehc_realman::Water2RequestSplitter splitter_;
  mutable std::mutex mutex_;
  std::vector<Request> requests_;
  double x_ = 0.0, y_ = 0.0, theta_ = 0.0;
  double joy_v_ = 0.0, joy_w_ = 0.0, joy_time_ = -1e9;
};

}  // namespace ehc_realman_test
