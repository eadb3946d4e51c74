// What the MQTT tests start: child processes (a Mosquitto broker on a free loopback port with a
// configuration the test writes, `mosquitto_sub`, `cncore serve`), and the subscriber's lines.
#pragma once

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <pwd.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

extern char** environ;

namespace mqtt_test {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

inline std::string read_text(const fs::path& p) {
  std::ifstream f(p);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

inline void write_text(const fs::path& p, const std::string& text) {
  std::ofstream(p) << text;
}

// A TCP port on 127.0.0.1 that nothing listens on (the kernel's pick; free when returned).
inline std::uint16_t free_port() {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a);
  socklen_t len = sizeof a;
  getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len);
  close(fd);
  return ntohs(a.sin_port);
}

inline bool port_open(std::uint16_t port) {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(port);
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  const bool ok = connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0;
  close(fd);
  return ok;
}

// The first of the places a Debian package puts a program (sbin is not on every PATH).
inline std::string find_program(const std::string& name) {
  for (const char* dir : {"/usr/bin/", "/usr/sbin/", "/usr/local/bin/", "/usr/local/sbin/"}) {
    if (access((std::string(dir) + name).c_str(), X_OK) == 0) return std::string(dir) + name;
  }
  return {};
}

// A child process with its standard input from a file (or /dev/null) and its output in a file.
class Process {
 public:
  Process(const std::vector<std::string>& argv, const fs::path& out,
          const std::string& stdin_file = "/dev/null")
      : out_(out) {
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, 0, stdin_file.c_str(), O_RDONLY, 0);
    posix_spawn_file_actions_addopen(&fa, 1, out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&fa, 1, 2);
    std::vector<char*> args;
    for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    if (posix_spawn(&pid_, args[0], &fa, nullptr, args.data(), environ) != 0) pid_ = -1;
    posix_spawn_file_actions_destroy(&fa);
  }
  ~Process() {
    if (!exit_code_ && pid_ > 0) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
  }
  Process(const Process&) = delete;
  Process& operator=(const Process&) = delete;

  bool started() const { return pid_ > 0; }
  void signal(int sig) const { kill(pid_, sig); }
  std::string output() const { return read_text(out_); }
  // The exit code (128 + signal when killed), or nothing if it still runs after `timeout`.
  std::optional<int> wait(std::chrono::milliseconds timeout) {
    const auto end = std::chrono::steady_clock::now() + timeout;
    while (!exit_code_) {
      int st = 0;
      if (waitpid(pid_, &st, WNOHANG) == pid_) {
        exit_code_ = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
        break;
      }
      if (std::chrono::steady_clock::now() > end) break;
      std::this_thread::sleep_for(10ms);
    }
    return exit_code_;
  }
  bool wait_output(const std::string& text, std::chrono::milliseconds timeout) const {
    const auto end = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < end) {
      if (output().find(text) != std::string::npos) return true;
      std::this_thread::sleep_for(10ms);
    }
    return false;
  }

 private:
  fs::path out_;
  pid_t pid_ = -1;
  std::optional<int> exit_code_;
};

// TLS and login settings shared by the broker and its clients.
struct BrokerSecurity {
  fs::path ca, cert, key;  // TLS when set: the test CA and the broker's certificate
  fs::path password_file;  // logins required when set (mosquitto_passwd format)
};

// A Mosquitto broker on a free loopback port, stopped with the object.
class Broker {
 public:
  // port 0: a free one.
  explicit Broker(const fs::path& dir, const BrokerSecurity& sec = {}, std::uint16_t port = 0)
      : port_(port != 0 ? port : free_port()) {
    const passwd* me = getpwuid(getuid());
    std::string conf = "listener " + std::to_string(port_) + " 127.0.0.1\n";
    conf += "persistence false\n";
    conf += "user " + std::string(me != nullptr ? me->pw_name : "root") + "\n";
    conf += "log_dest stdout\n";
    if (sec.password_file.empty()) {
      conf += "allow_anonymous true\n";
    } else {
      conf += "allow_anonymous false\npassword_file " + sec.password_file.string() + "\n";
    }
    if (!sec.cert.empty()) {
      conf += "cafile " + sec.ca.string() + "\ncertfile " + sec.cert.string() + "\nkeyfile " +
              sec.key.string() + "\n";
    }
    const fs::path conf_file = dir / "mosquitto.conf";
    write_text(conf_file, conf);
    process_.emplace(std::vector<std::string>{find_program("mosquitto"), "-c", conf_file.string()},
                     dir / "mosquitto.log");
    const auto end = std::chrono::steady_clock::now() + 10s;
    while (!port_open(port_) && std::chrono::steady_clock::now() < end) {
      std::this_thread::sleep_for(20ms);
    }
  }
  std::uint16_t port() const { return port_; }
  bool running() { return port_open(port_); }
  std::string log() const { return process_->output(); }

 private:
  std::uint16_t port_;
  std::optional<Process> process_;
};

// One message as `mosquitto_sub -v` prints it: topic, a space, payload.
struct Received {
  std::string topic, payload;
};

// `mosquitto_sub -v` on PREFIX/#, ready when its own probe message has come back.
class Subscriber {
 public:
  Subscriber(const fs::path& dir, std::uint16_t port, const std::string& prefix,
             const std::vector<std::string>& extra = {})
      : out_(dir / "sub.txt") {
    std::vector<std::string> common = {"-h", "127.0.0.1", "-p", std::to_string(port)};
    common.insert(common.end(), extra.begin(), extra.end());
    std::vector<std::string> sub = {
        find_program("mosquitto_sub"), "-v", "-q", "1", "-t", prefix + "/#"};
    sub.insert(sub.end(), common.begin(), common.end());
    process_.emplace(sub, out_);
    std::vector<std::string> pub = {
        find_program("mosquitto_pub"), "-q", "1", "-t", prefix + "/probe", "-m", "ready"};
    pub.insert(pub.end(), common.begin(), common.end());
    const auto end = std::chrono::steady_clock::now() + 10s;
    while (!ready_ && std::chrono::steady_clock::now() < end) {
      Process p(pub, dir / "pub.txt");
      p.wait(5s);
      ready_ = process_->wait_output(prefix + "/probe ready", 500ms);
    }
  }
  bool ready() const { return ready_; }
  std::vector<Received> messages() const {
    std::vector<Received> out;
    std::istringstream in(read_text(out_));
    std::string line;
    while (std::getline(in, line)) {
      const std::size_t sp = line.find(' ');
      if (sp == std::string::npos || line.ends_with("/probe ready")) continue;
      out.push_back({line.substr(0, sp), line.substr(sp + 1)});
    }
    return out;
  }
  bool wait_for(const std::string& text, std::chrono::milliseconds timeout) const {
    return process_->wait_output(text, timeout);
  }

 private:
  fs::path out_;
  std::optional<Process> process_;
  bool ready_ = false;
};

}  // namespace mqtt_test
