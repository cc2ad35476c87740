#include "ehc_sim/water2_api_server.h"

#include "ehc_realman/water2_client.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <stdexcept>

namespace ehc_sim {

Water2ApiServer::Water2ApiServer(int port) : port_(port) {
  listen_fd_ = ehc_realman::listenOnLoopback(&port_, /*nonblocking=*/true, "Water2ApiServer");
}

Water2ApiServer::~Water2ApiServer() {
  closeClient();
  if (listen_fd_ >= 0) ::close(listen_fd_);
}

void Water2ApiServer::closeClient() {
  if (client_fd_ >= 0) ::close(client_fd_);
  client_fd_ = -1;
  splitter_.clear();
}

void Water2ApiServer::send(const std::string& text) {
  std::size_t done = 0;
  while (done < text.size() && client_fd_ >= 0) {
    const ssize_t n = ::send(client_fd_, text.data() + done, text.size() - done, MSG_NOSIGNAL);
    if (n > 0) {
      done += static_cast<std::size_t>(n);
    } else if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR)) {
      pollfd p{client_fd_, POLLOUT, 0};
      if (::poll(&p, 1, 100) <= 0) closeClient();  // a client that reads nothing is dropped
    } else {
      closeClient();
    }
  }
}

void Water2ApiServer::serve(double timeout_s, const JoyHandler& on_joy, const PoseSource& status_pose) {
  pollfd fds[2] = {{listen_fd_, POLLIN, 0}, {client_fd_, POLLIN, 0}};
  const int wait_ms = std::isfinite(timeout_s) && timeout_s > 0.0 ? static_cast<int>(std::ceil(timeout_s * 1e3)) : 0;
  if (::poll(fds, client_fd_ >= 0 ? 2 : 1, wait_ms) <= 0) return;
  if (fds[0].revents & POLLIN) {
    const int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC | SOCK_NONBLOCK);
    if (fd >= 0) {
      closeClient();
      client_fd_ = fd;
      const int one = 1;
      ::setsockopt(client_fd_, IPPROTO_TCP, TCP_NODELAY, &one, sizeof(one));
      ++counters_.connections;
      return;  // its requests come on the next call
    }
  }
  if (client_fd_ < 0 || !(fds[1].revents & (POLLIN | POLLHUP | POLLERR))) return;
  char buf[4096];
  const ssize_t n = ::recv(client_fd_, buf, sizeof(buf), 0);
  if (n == 0 || (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR)) {
    closeClient();
    return;
  }
  if (n < 0) return;
  splitter_.feed(buf, static_cast<std::size_t>(n));
  std::string text;
  while (client_fd_ >= 0 && splitter_.next(text)) {
    const ehc_realman::Water2Request r = ehc_realman::parseWater2Request(text);
    if (r.joy) {
      ++counters_.joy_controls;
      on_joy(r.linear, r.angular);
      send(ehc_realman::water2ResponseJson(r.command, "OK", ""));
    } else if (r.command == "/api/robot_status") {
      ++counters_.status_requests;
      send(ehc_realman::water2ResponseJson(r.command, "OK", "", status_pose()));
    } else {
      ++counters_.bad_requests;
      send(ehc_realman::water2ResponseJson(r.command, "INVALID_REQUEST", "unknown or malformed request"));
    }
  }
}

}  // namespace ehc_sim
