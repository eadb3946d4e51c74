// The SHDR server thread: polls the controller's status at the sample rate, sends what changed to
// every connected agent, a full snapshot to a new one, and answers `* PING` with `* PONG <ms>`.
// Anything else an agent sends is ignored: telemetry never commands the machine.
#include <arpa/inet.h>
#include <fcntl.h>
#include <fmt/format.h>
#include <netdb.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <mutex>
#include <stdexcept>
#include <thread>

#include "telemetry/telemetry.hpp"

namespace cncore::telemetry {
namespace {

// Output queued for an agent beyond this means it stopped reading: it is dropped (an agent
// reconnects and gets a fresh snapshot).
constexpr std::size_t kMaxQueuedBytes = 1U << 20;

struct Client {
  int fd = -1;
  std::string in, out;
};

std::pair<std::string, std::string> split_address(const std::string& address) {
  const std::size_t colon = address.rfind(':');
  if (colon == std::string::npos || colon + 1 == address.size()) {
    throw std::runtime_error(fmt::format("--mtconnect {}: expected HOST:PORT", address));
  }
  return {address.substr(0, colon), address.substr(colon + 1)};
}

int listen_on(const std::string& address) {
  const auto [host, port] = split_address(address);
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  hints.ai_flags = AI_PASSIVE | AI_NUMERICSERV;
  addrinfo* found = nullptr;
  if (const int rc = getaddrinfo(host.c_str(), port.c_str(), &hints, &found); rc != 0) {
    throw std::runtime_error(fmt::format("--mtconnect {}: {}", address, gai_strerror(rc)));
  }
  int fd = -1;
  std::string why = "no address";
  for (addrinfo* a = found; a != nullptr && fd < 0; a = a->ai_next) {
    fd = socket(a->ai_family, a->ai_socktype | SOCK_CLOEXEC | SOCK_NONBLOCK, a->ai_protocol);
    if (fd < 0) continue;
    const int one = 1;
    setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    if (bind(fd, a->ai_addr, a->ai_addrlen) != 0 || listen(fd, 8) != 0) {
      why = std::strerror(errno);
      close(fd);
      fd = -1;
    }
  }
  freeaddrinfo(found);
  if (fd < 0) throw std::runtime_error(fmt::format("--mtconnect {}: {}", address, why));
  return fd;
}

}  // namespace

struct ShdrAdapter::Impl {
  const runtime::Controller& controller;
  ShdrOptions options;
  int listen_fd = -1;
  std::uint16_t port = 0;
  std::vector<Client> clients;
  std::vector<ShdrItem> last;  // the items as last sent
  std::mutex program_mutex;
  std::string program;
  std::atomic<bool> stop{false};
  std::thread thread;

  Impl(const runtime::Controller& c, ShdrOptions o) : controller(c), options(std::move(o)) {}

  void run() {
    const auto period = std::chrono::duration<double>(1.0 / options.sample_hz);
    auto next = std::chrono::steady_clock::now();
    while (!stop.load()) {
      const auto now = std::chrono::steady_clock::now();
      if (now >= next) {
        publish();
        next += std::chrono::duration_cast<std::chrono::steady_clock::duration>(period);
        if (next < now) next = now;
      }
      const auto wait_ms = std::chrono::duration_cast<std::chrono::milliseconds>(next - now);
      serve_io(static_cast<int>(std::clamp<long long>(wait_ms.count(), 1, 100)));
    }
    for (const Client& c : clients) close(c.fd);
    clients.clear();
  }

  std::string program_name() {
    const std::lock_guard lock(program_mutex);
    return program;
  }

  // Sends the items that changed since the last poll to every agent.
  void publish() {
    std::vector<ShdrItem> items = mtconnect_items(controller.status(), program_name());
    std::vector<const ShdrItem*> changed;
    for (std::size_t i = 0; i < items.size(); ++i) {
      if (i >= last.size() || last[i].fields != items[i].fields) changed.push_back(&items[i]);
    }
    if (!changed.empty()) {
      std::string text;
      for (const std::string& l :
           shdr_lines(shdr_timestamp(std::chrono::system_clock::now()), changed)) {
        text += l + "\n";
      }
      for (Client& c : clients) c.out += text;
    }
    last = std::move(items);
  }

  std::string snapshot() const {
    std::vector<const ShdrItem*> all;
    all.reserve(last.size());
    for (const ShdrItem& i : last) all.push_back(&i);
    std::string text;
    for (const std::string& l : shdr_lines(shdr_timestamp(std::chrono::system_clock::now()), all)) {
      text += l + "\n";
    }
    return text;
  }

  void serve_io(int timeout_ms) {
    std::vector<pollfd> fds;
    fds.push_back({listen_fd, POLLIN, 0});
    for (const Client& c : clients) {
      fds.push_back({c.fd, static_cast<short>(POLLIN | (c.out.empty() ? 0 : POLLOUT)), 0});
    }
    if (poll(fds.data(), fds.size(), timeout_ms) <= 0) return;
    for (std::size_t i = 1; i < fds.size(); ++i) {
      Client& c = clients[i - 1];
      if ((fds[i].revents & (POLLIN | POLLHUP | POLLERR)) != 0) receive(c);
      if (c.fd >= 0 && !c.out.empty()) send_queued(c);
    }
    std::erase_if(clients, [](const Client& c) { return c.fd < 0; });
    if ((fds[0].revents & POLLIN) != 0) accept_agent();
  }

  void accept_agent() {
    const int fd = accept4(listen_fd, nullptr, nullptr, SOCK_CLOEXEC | SOCK_NONBLOCK);
    if (fd < 0) return;
    if (last.empty()) last = mtconnect_items(controller.status(), program_name());
    Client c{fd, {}, snapshot()};
    send_queued(c);
    if (c.fd >= 0) clients.push_back(std::move(c));
  }

  void receive(Client& c) {
    char buf[1024];
    const ssize_t n = recv(c.fd, buf, sizeof buf, 0);
    if (n == 0 || (n < 0 && errno != EAGAIN && errno != EINTR)) {
      drop(c);
      return;
    }
    if (n < 0) return;
    c.in.append(buf, static_cast<std::size_t>(n));
    for (std::size_t nl = c.in.find('\n'); nl != std::string::npos; nl = c.in.find('\n')) {
      std::string line = c.in.substr(0, nl);
      c.in.erase(0, nl + 1);
      if (!line.empty() && line.back() == '\r') line.pop_back();
      if (line.starts_with("* PING")) c.out += fmt::format("* PONG {}\n", options.heartbeat_ms);
    }
    if (c.in.size() > 4096) drop(c);  // no line end in sight: not an agent
  }

  void send_queued(Client& c) {
    while (!c.out.empty()) {
      const ssize_t n = send(c.fd, c.out.data(), c.out.size(), MSG_NOSIGNAL);
      if (n < 0 && (errno == EAGAIN || errno == EINTR)) break;
      if (n <= 0) {
        drop(c);
        return;
      }
      c.out.erase(0, static_cast<std::size_t>(n));
    }
    if (c.out.size() > kMaxQueuedBytes) drop(c);
  }

  static void drop(Client& c) {
    if (c.fd >= 0) close(c.fd);
    c.fd = -1;
    c.out.clear();
  }
};

ShdrAdapter::ShdrAdapter(const runtime::Controller& controller, ShdrOptions options)
    : impl_(std::make_unique<Impl>(controller, std::move(options))) {
  if (!(impl_->options.sample_hz > 0 && impl_->options.sample_hz <= 1000)) {
    throw std::runtime_error("the SHDR sample rate must be in (0, 1000] Hz");
  }
  impl_->listen_fd = listen_on(impl_->options.address);
  sockaddr_storage bound{};
  socklen_t len = sizeof bound;
  getsockname(impl_->listen_fd, reinterpret_cast<sockaddr*>(&bound), &len);
  impl_->port =
      ntohs(bound.ss_family == AF_INET6 ? reinterpret_cast<const sockaddr_in6*>(&bound)->sin6_port
                                        : reinterpret_cast<const sockaddr_in*>(&bound)->sin_port);
  impl_->thread = std::thread([this] { impl_->run(); });
}

ShdrAdapter::~ShdrAdapter() {
  impl_->stop.store(true);
  impl_->thread.join();
  close(impl_->listen_fd);
}

std::uint16_t ShdrAdapter::port() const {
  return impl_->port;
}

void ShdrAdapter::set_program(const std::string& name) {
  const std::lock_guard lock(impl_->program_mutex);
  impl_->program = name;
}

}  // namespace cncore::telemetry
