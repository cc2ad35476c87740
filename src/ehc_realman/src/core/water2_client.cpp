#include "ehc_realman/water2_client.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <utility>

namespace ehc_realman {

namespace {
int toMillis(double seconds) {
  if (!(seconds > 0.0)) return 0;
  return static_cast<int>(std::min(std::ceil(seconds * 1000.0), 60000.0));
}
}  // namespace

Water2Client::Water2Client(Water2ClientConfig config)
    : config_(std::move(config)), splitter_(config_.max_object_bytes) {
  if (config_.port < 1 || config_.port > 65535)
    throw std::invalid_argument("[Water2Client] port must be in 1..65535");
  if (config_.host.empty()) throw std::invalid_argument("[Water2Client] host must not be empty");
}

Water2Client::~Water2Client() { close(); }

void Water2Client::close() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

void Water2Client::failAndClose(const std::string& what) {
  close();
  throw std::runtime_error("[Water2Client] " + config_.host + ":" + std::to_string(config_.port) +
                           ": " + what);
}

void Water2Client::connect() {
  close();
  splitter_.clear();
  addrinfo hints{};
  hints.ai_family = AF_INET;
  hints.ai_socktype = SOCK_STREAM;
  addrinfo* found = nullptr;
  const int rc = ::getaddrinfo(config_.host.c_str(), std::to_string(config_.port).c_str(), &hints,
                               &found);
  if (rc != 0 || found == nullptr)
    failAndClose(std::string("cannot resolve host (") + gai_strerror(rc) + ")");
  sockaddr_in addr{};
  std::memcpy(&addr, found->ai_addr, std::min<std::size_t>(sizeof(addr), found->ai_addrlen));
  ::freeaddrinfo(found);

  fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd_ < 0) failAndClose(std::string("socket: ") + std::strerror(errno));
  const int one = 1;
  ::setsockopt(fd_, IPPROTO_TCP, TCP_NODELAY, &one, sizeof(one));  // one request per segment
  if (::connect(fd_, reinterpret_cast<const sockaddr*>(&addr), sizeof(addr)) != 0) {
    if (errno != EINPROGRESS) failAndClose(std::string("connect: ") + std::strerror(errno));
    pollfd p{fd_, POLLOUT, 0};
    const int n = ::poll(&p, 1, toMillis(config_.connect_timeout));
    if (n == 0) failAndClose("connect timed out");
    if (n < 0) failAndClose(std::string("poll: ") + std::strerror(errno));
    int err = 0;
    socklen_t len = sizeof(err);
    ::getsockopt(fd_, SOL_SOCKET, SO_ERROR, &err, &len);
    if (err != 0) failAndClose(std::string("connect: ") + std::strerror(err));
  }
}

void Water2Client::send(const std::string& request) {
  if (fd_ < 0) throw std::runtime_error("[Water2Client] send: not connected");
  const std::string data = request + config_.terminator;
  std::size_t done = 0;
  while (done < data.size()) {
    const ssize_t n =
        ::send(fd_, data.data() + done, data.size() - done, MSG_NOSIGNAL | MSG_DONTWAIT);
    if (n < 0) {
      if (errno == EINTR) continue;
      failAndClose(std::string("send: ") + std::strerror(errno));
    }
    done += static_cast<std::size_t>(n);
  }
}

std::vector<std::string> Water2Client::receive(double timeout_s) {
  if (fd_ < 0) throw std::runtime_error("[Water2Client] receive: not connected");
  std::vector<std::string> out;
  pollfd p{fd_, POLLIN, 0};
  const int n = ::poll(&p, 1, toMillis(timeout_s));
  if (n < 0 && errno != EINTR) failAndClose(std::string("poll: ") + std::strerror(errno));
  if (n > 0) {
    // Drain what is there, bounded: at most 16 reads of 4 KiB per call.
    char buf[4096];
    for (int reads = 0; reads < 16; ++reads) {
      const ssize_t r = ::recv(fd_, buf, sizeof(buf), MSG_DONTWAIT);
      if (r == 0) failAndClose("connection closed by the base");
      if (r < 0) {
        if (errno == EAGAIN || errno == EWOULDBLOCK) break;
        if (errno == EINTR) continue;
        failAndClose(std::string("recv: ") + std::strerror(errno));
      }
      splitter_.feed(buf, static_cast<std::size_t>(r));
      if (static_cast<std::size_t>(r) < sizeof(buf)) break;
    }
  }
  std::string obj;
  while (splitter_.next(obj)) out.push_back(std::move(obj));
  return out;
}

int listenOnLoopback(int* port, bool nonblocking, const std::string& owner) {
  if (*port < 0 || *port > 65535)
    throw std::runtime_error("[" + owner + "] port " + std::to_string(*port) + " is not in [0, 65535]");
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC | (nonblocking ? SOCK_NONBLOCK : 0), 0);
  if (fd < 0) throw std::runtime_error("[" + owner + "] socket: " + std::strerror(errno));
  const int one = 1;
  ::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof(one));
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);  // 127.0.0.1 only
  addr.sin_port = htons(static_cast<uint16_t>(*port));
  if (::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)) != 0 || ::listen(fd, 4) != 0) {
    const std::string why = std::strerror(errno);
    ::close(fd);
    throw std::runtime_error("[" + owner + "] cannot listen on 127.0.0.1:" + std::to_string(*port) + ": " + why);
  }
  socklen_t len = sizeof(addr);
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len);
  *port = ntohs(addr.sin_port);
  return fd;
}

}  // namespace ehc_realman
