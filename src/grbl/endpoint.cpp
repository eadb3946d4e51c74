#include "grbl/endpoint.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

namespace cncore::grbl {

namespace {

constexpr int kPollMs = 2;  // how often a connection looks at the machine while a sender is there
constexpr std::size_t kReadAhead = 4 * kRxBufferBytes;  // beyond this, the kernel's buffers wait

std::runtime_error sys_error(const std::string& what) {
  return std::runtime_error(what + ": " + std::strerror(errno));
}

}  // namespace

std::unique_ptr<Endpoint> Endpoint::tcp(runtime::Controller& c, SharedSettings& s,
                                        const std::string& host_port) {
  const auto colon = host_port.rfind(':');
  if (colon == std::string::npos) {
    throw std::runtime_error("--grbl-tcp " + host_port + ": expected HOST:PORT");
  }
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  const int port = std::atoi(host_port.c_str() + colon + 1);
  if (port <= 0 || port > 65535 ||
      ::inet_pton(AF_INET, host_port.substr(0, colon).c_str(), &addr.sin_addr) != 1) {
    throw std::runtime_error("--grbl-tcp " + host_port + ": expected an IPv4 HOST:PORT");
  }
  addr.sin_port = htons(static_cast<std::uint16_t>(port));
  std::unique_ptr<Endpoint> e(new Endpoint(c, s));
  e->listen_fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (e->listen_fd_ < 0) throw sys_error("--grbl-tcp socket");
  const int one = 1;
  ::setsockopt(e->listen_fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
  if (::bind(e->listen_fd_, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0) {
    throw sys_error("--grbl-tcp " + host_port);
  }
  if (::listen(e->listen_fd_, 4) != 0) throw sys_error("--grbl-tcp listen");
  e->description_ = "Grbl on tcp " + host_port;
  e->thread_ = std::thread([p = e.get()] { p->run_tcp(); });
  return e;
}

std::unique_ptr<Endpoint> Endpoint::pty(runtime::Controller& c, SharedSettings& s,
                                        const std::string& link_path) {
  std::unique_ptr<Endpoint> e(new Endpoint(c, s));
  e->master_fd_ = ::posix_openpt(O_RDWR | O_NOCTTY | O_CLOEXEC);
  if (e->master_fd_ < 0) throw sys_error("--grbl-pty posix_openpt");
  if (::grantpt(e->master_fd_) != 0 || ::unlockpt(e->master_fd_) != 0) {
    throw sys_error("--grbl-pty grantpt/unlockpt");
  }
  const char* slave = ::ptsname(e->master_fd_);
  if (slave == nullptr) throw sys_error("--grbl-pty ptsname");
  const std::string slave_path = slave;
  // Raw mode on the line discipline: no echo of what cncore writes, no line editing. It stays
  // with the terminal while the master is open.
  const int sfd = ::open(slave_path.c_str(), O_RDWR | O_NOCTTY | O_CLOEXEC);
  if (sfd < 0) throw sys_error("--grbl-pty " + slave_path);
  termios t{};
  ::tcgetattr(sfd, &t);
  ::cfmakeraw(&t);
  ::cfsetspeed(&t, B115200);
  ::tcsetattr(sfd, TCSANOW, &t);
  ::close(sfd);
  struct stat st {};
  if (::lstat(link_path.c_str(), &st) == 0) {
    if (!S_ISLNK(st.st_mode)) {
      throw std::runtime_error("--grbl-pty " + link_path + ": exists and is not a link");
    }
    ::unlink(link_path.c_str());
  }
  if (::symlink(slave_path.c_str(), link_path.c_str()) != 0) {
    throw sys_error("--grbl-pty " + link_path);
  }
  e->link_path_ = link_path;
  e->description_ = "Grbl on pty " + link_path + " -> " + slave_path;
  e->thread_ = std::thread([p = e.get()] { p->run_pty(); });
  return e;
}

Endpoint::~Endpoint() {
  stop_.store(true);
  if (thread_.joinable()) thread_.join();
  if (listen_fd_ >= 0) ::close(listen_fd_);
  if (master_fd_ >= 0) ::close(master_fd_);
  if (!link_path_.empty()) ::unlink(link_path_.c_str());
}

bool Endpoint::write_all(int fd, const std::string& text) const {
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = fd == master_fd_
                          ? ::write(fd, text.data() + done, text.size() - done)
                          : ::send(fd, text.data() + done, text.size() - done, MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && errno == EAGAIN) {
      pollfd p{fd, POLLOUT, 0};
      if (::poll(&p, 1, 1000) <= 0 || stop_.load()) return false;
      continue;
    }
    if (n <= 0) return false;
    done += static_cast<std::size_t>(n);
  }
  return true;
}

bool Endpoint::serve(int fd, bool readable) {
  std::string out;
  bool alive = true;
  {
    const std::lock_guard lock(shared_.mutex);
    if (readable && connection_->buffered_bytes() < kReadAhead) {
      char buf[512];
      const ssize_t n = ::read(fd, buf, sizeof buf);
      if (n > 0) {
        connection_->receive(std::string_view(buf, static_cast<std::size_t>(n)), out);
      } else if (n == 0 || (errno != EAGAIN && errno != EINTR)) {
        alive = false;
      }
    } else {
      connection_->poll(out);
    }
  }
  if (!out.empty() && !write_all(fd, out)) alive = false;
  return alive;
}

void Endpoint::run_tcp() {
  int client = -1;
  while (!stop_.load()) {
    pollfd p[2] = {{listen_fd_, POLLIN, 0}, {client, POLLIN, 0}};
    const bool room = connection_ && connection_->buffered_bytes() < kReadAhead;
    if (!room) p[1].events = 0;
    const int rc = ::poll(p, client >= 0 ? 2 : 1, client >= 0 ? kPollMs : 50);
    if (rc < 0 && errno != EINTR) break;
    // The client first: a sender that has just hung up makes room for the next one.
    if (client >= 0 && !serve(client, (p[1].revents & (POLLIN | POLLHUP | POLLERR)) != 0)) {
      ::close(client);
      client = -1;
    }
    if ((p[0].revents & POLLIN) != 0) {
      const int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC | SOCK_NONBLOCK);
      if (fd >= 0 && client >= 0) {
        const std::string busy = "[MSG:another sender is connected to this endpoint]\r\n";
        (void)::send(fd, busy.data(), busy.size(), MSG_NOSIGNAL);
        ::close(fd);
      } else if (fd >= 0) {
        client = fd;
        const int one = 1;
        ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
        std::string out;
        {
          const std::lock_guard lock(shared_.mutex);
          connection_ = std::make_unique<Connection>(controller_, shared_.store);
          connection_->connect(out);
        }
        if (!write_all(client, out)) {
          ::close(client);
          client = -1;
        }
      }
    }
  }
  if (client >= 0) ::close(client);
}

void Endpoint::run_pty() {
  ::fcntl(master_fd_, F_SETFL, ::fcntl(master_fd_, F_GETFL) | O_NONBLOCK);
  bool connected = false;
  while (!stop_.load()) {
    pollfd p{master_fd_, POLLIN, 0};
    const bool room = connection_ && connection_->buffered_bytes() < kReadAhead;
    if (connected && !room) p.events = 0;
    const int rc = ::poll(&p, 1, connected ? kPollMs : 20);
    if (rc < 0 && errno != EINTR) break;
    // POLLHUP: no process has the slave open (no sender).
    if ((p.revents & POLLHUP) != 0) {
      connected = false;
      ::usleep(20000);
      continue;
    }
    if (!connected) {
      connected = true;
      std::string out;
      {
        const std::lock_guard lock(shared_.mutex);
        connection_ = std::make_unique<Connection>(controller_, shared_.store);
        connection_->connect(out);
      }
      (void)write_all(master_fd_, out);
    }
    if (!serve(master_fd_, (p.revents & POLLIN) != 0)) connected = false;
  }
}

}  // namespace cncore::grbl
