// The operator's web page of `cncore serve --http ADDR` (docs/hmi.md): an HTTP server that
// serves the page (HTML, JavaScript, three.js and uPlot compiled into the binary), streams the
// controller's status as Server-Sent Events and turns posted controls into runtime::Controller
// calls. It knows the control interface only, and reads programs to draw their path.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "runtime/control.hpp"

namespace cncore::hmi {

struct HttpOptions {
  std::string address = "127.0.0.1:8080";  // HOST:PORT (port 0: any free port)
  // Every control must carry it (`Authorization: Bearer TOKEN`); viewers without it read only.
  // Empty: none, allowed on a loopback address only.
  std::string token;
  double status_hz = 25;        // status events per second to each viewer
  std::size_t max_viewers = 8;  // event streams at once (each holds a server thread)
  std::string upload_dir;       // where uploaded programs go; empty: a temporary folder
};

// HOST of HOST:PORT is a loopback address (127.0.0.0/8, ::1, localhost).
bool is_loopback(const std::string& host);
// Splits HOST:PORT ([::1]:PORT for IPv6). Throws std::runtime_error when malformed.
std::pair<std::string, std::uint16_t> split_address(const std::string& address);

class HttpServer {
 public:
  // Listens at once and serves on its own threads. Throws std::runtime_error when the address
  // is malformed or cannot be bound, or is not loopback and no token is given.
  HttpServer(runtime::Controller& controller, HttpOptions options);
  // Ends the event streams and joins the server's threads.
  ~HttpServer();
  HttpServer(const HttpServer&) = delete;
  HttpServer& operator=(const HttpServer&) = delete;

  std::uint16_t port() const;
  std::string url() const;  // http://HOST:PORT/
  // A program the controller has loaded by another way (--program): the page draws it.
  void program_loaded(const std::string& path);
  // A message for the operator (the controller's take_message(), which its owner reads): shown
  // on the page.
  void post_message(const std::string& text);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace cncore::hmi
