// The transports of the Grbl endpoint: a TCP listener on loopback (`--grbl-tcp 127.0.0.1:2323`,
// like grblHAL's network streaming) and a pseudo-terminal whose slave is linked at a path
// (`--grbl-pty PATH`, for senders that open a serial port). Each runs one Connection on its own
// thread; the connections of one process share the settings (and their lock).
#pragma once

#include <atomic>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "grbl/connection.hpp"
#include "runtime/control.hpp"

namespace cncore::grbl {

struct SharedSettings {
  SettingsStore store;
  std::mutex mutex;  // held while a connection runs (the connections of both endpoints)
};

class Endpoint {
 public:
  // Throws std::runtime_error when the address cannot be bound or the terminal not created.
  static std::unique_ptr<Endpoint> tcp(runtime::Controller& c, SharedSettings& s,
                                       const std::string& host_port);
  static std::unique_ptr<Endpoint> pty(runtime::Controller& c, SharedSettings& s,
                                       const std::string& link_path);
  ~Endpoint();  // stops the thread, closes the client, removes the pty link
  Endpoint(const Endpoint&) = delete;
  Endpoint& operator=(const Endpoint&) = delete;

  const std::string& description() const { return description_; }

 private:
  Endpoint(runtime::Controller& c, SharedSettings& s) : controller_(c), shared_(s) {}
  void run_tcp();
  void run_pty();
  // Reads what the client sent (bounded by the connection's buffer), runs the connection, writes
  // the replies. False: the client is gone.
  bool serve(int fd, bool readable);
  bool write_all(int fd, const std::string& text) const;

  runtime::Controller& controller_;
  SharedSettings& shared_;
  std::unique_ptr<Connection> connection_;
  int listen_fd_ = -1;
  int master_fd_ = -1;
  std::string link_path_;
  std::string description_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace cncore::grbl
