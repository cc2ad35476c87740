#pragma once
// Water2Client: a small POSIX TCP client for the Water2 base API. Every call is bounded in time
// (connect timeout, receive timeout) and memory (JsonObjectSplitter); failures throw
// std::runtime_error "[Water2Client] ..." and leave the client disconnected, ready to reconnect.

#include "ehc_realman/water2_protocol.h"

#include <string>
#include <vector>

namespace ehc_realman {

struct Water2ClientConfig {
  std::string host = "192.168.10.10";  ///< IPv4 address or host name
  int port = 31001;
  double connect_timeout = 0.5;        ///< s
  std::string terminator;              ///< appended to each request ("" as the vendor examples)
  std::size_t max_object_bytes = 65536;
};

class Water2Client {
 public:
  explicit Water2Client(Water2ClientConfig config);
  ~Water2Client();
  Water2Client(const Water2Client&) = delete;
  Water2Client& operator=(const Water2Client&) = delete;

  /// Closes any previous connection and connects within connect_timeout. Throws on failure.
  void connect();
  bool isConnected() const { return fd_ >= 0; }
  void close();

  /// Sends one request (+ terminator). Throws (and closes) if the socket fails or would block.
  void send(const std::string& request);
  /// Waits at most timeout_s for data, reads what is available and returns the complete JSON
  /// objects received so far. Throws (and closes) on end of stream or socket error.
  std::vector<std::string> receive(double timeout_s);

  const JsonObjectSplitter& splitter() const { return splitter_; }
  const Water2ClientConfig& config() const { return config_; }

 private:
  [[noreturn]] void failAndClose(const std::string& what);

  Water2ClientConfig config_;
  int fd_ = -1;
  JsonObjectSplitter splitter_;
};

/// The base's side of the TCP link (the hardware stand-in, the tests' fake base): a socket
/// listening on 127.0.0.1:`*port` (0: an ephemeral port, written back to `*port`). Throws
/// std::runtime_error "[owner] ..." when it cannot listen.
int listenOnLoopback(int* port, bool nonblocking, const std::string& owner);

}  // namespace ehc_realman
