// The MQTT publisher's thread and its connection (Eclipse Paho's asynchronous C++ client): reads
// the controller's status, hands MqttTopics' messages to Paho without waiting, keeps at most
// `max_pending` of them queued and counts the rest as dropped, and reconnects with a growing
// pause. Nothing is subscribed: no message from the broker reaches the controller.
#include <fmt/format.h>
#include <mqtt/async_client.h>
#include <netdb.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <deque>
#include <mutex>
#include <stdexcept>
#include <thread>

#include "telemetry/telemetry.hpp"

namespace cncore::telemetry {

namespace {

// Whether HOST:PORT accepts a TCP connection within a second.
bool tcp_reachable(const std::string& host, std::uint16_t port) {
  addrinfo hints{};
  hints.ai_socktype = SOCK_STREAM;
  addrinfo* found = nullptr;
  if (::getaddrinfo(host.c_str(), std::to_string(port).c_str(), &hints, &found) != 0) return false;
  bool ok = false;
  for (addrinfo* a = found; a != nullptr && !ok; a = a->ai_next) {
    const int fd = ::socket(a->ai_family, a->ai_socktype | SOCK_NONBLOCK, a->ai_protocol);
    if (fd < 0) continue;
    if (::connect(fd, a->ai_addr, a->ai_addrlen) == 0) {
      ok = true;
    } else if (errno == EINPROGRESS) {
      pollfd p{fd, POLLOUT, 0};
      int err = 0;
      socklen_t len = sizeof err;
      ok = ::poll(&p, 1, 1000) == 1 && ::getsockopt(fd, SOL_SOCKET, SO_ERROR, &err, &len) == 0 &&
           err == 0;
    }
    ::close(fd);
  }
  ::freeaddrinfo(found);
  return ok;
}

using Steady = std::chrono::steady_clock;

// Events are looked for this often (a state that lasts less may be missed; cycle events never
// are: the status carries the job's first and last cycle).
constexpr auto kEventPoll = std::chrono::milliseconds(10);
constexpr auto kFirstRetry = std::chrono::seconds(1);
constexpr auto kLastRetry = std::chrono::seconds(30);

// MQTT 3.1.1 CONNACK return codes 4 and 5.
constexpr int kBadUserNameOrPassword = 4;
constexpr int kNotAuthorized = 5;

// Counts a message as pending from publish() until Paho reports it written (QoS 0) or
// acknowledged (QoS 1), or failed.
class PendingCounter : public mqtt::iaction_listener {
 public:
  std::atomic<std::size_t> pending{0};

 private:
  void on_success(const mqtt::token& /*token*/) override { pending.fetch_sub(1); }
  void on_failure(const mqtt::token& /*token*/) override { pending.fetch_sub(1); }
};

std::string read_client_id(const MqttOptions& o, const MqttTarget& t) {
  if (!o.client_id.empty()) return o.client_id;
  std::string id = "cncore-" + t.prefix;
  for (char& c : id) {
    const bool plain = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9');
    if (!plain && c != '-') c = '-';
  }
  return id;
}

}  // namespace

struct MqttPublisher::Impl {
  const runtime::Controller& controller;
  MqttOptions options;
  MqttTarget target;
  MqttTopics topics;
  mqtt::async_client client;
  mqtt::connect_options connect_options;
  PendingCounter pending;

  std::atomic<bool> connected{false};
  std::atomic<bool> need_birth{false};
  std::atomic<std::uint64_t> published{0};
  std::atomic<std::uint64_t> dropped{0};
  std::atomic<bool> stop{false};

  std::mutex mutex;  // guards the fields below
  std::string program;
  std::deque<std::string> messages;

  mqtt::token_ptr connecting;  // the publisher thread's connection attempt
  Steady::duration retry = kFirstRetry;
  Steady::time_point next_try;
  std::thread thread;

  Impl(const runtime::Controller& c, MqttOptions o, MqttTarget t)
      : controller(c),
        options(std::move(o)),
        target(std::move(t)),
        topics(target.prefix, c.machine()),
        client(target.server_uri(), read_client_id(options, target)),
        program(options.program) {}

  void say(std::string text) {
    const std::lock_guard lock(mutex);
    messages.push_back("mqtt: " + std::move(text));
  }

  std::string program_name() {
    const std::lock_guard lock(mutex);
    return program;
  }

  void build_connect_options() {
    const MqttMessage will = topics.offline(true);
    mqtt::connect_options_builder b;
    b.clean_session(true)
        .keep_alive_interval(std::chrono::seconds(10))
        .connect_timeout(std::chrono::duration_cast<std::chrono::seconds>(options.connect_timeout))
        .will(mqtt::message(will.topic, will.payload, will.qos, will.retain));
    if (!options.user.empty()) b.user_name(options.user).password(options.password);
    if (target.tls) {
      // No TLS error handler: Paho C++ 1.2 hands the C library a pointer into the copy of the
      // options that connect() takes by value, which is gone when the handshake fails (ASan:
      // stack-use-after-scope). failure() tells a refused handshake from a broker that is down.
      mqtt::ssl_options_builder ssl;
      ssl.enable_server_cert_auth(true).verify(true);
      if (!options.ca_file.empty()) ssl.trust_store(options.ca_file);
      b.ssl(ssl.finalize());
    }
    connect_options = b.finalize();
  }

  // Why a connection attempt failed, for the operator; `fatal`: retrying cannot help.
  std::string failure(int rc, const std::string& what, bool& fatal) {
    fatal = true;
    if (rc == kBadUserNameOrPassword || rc == kNotAuthorized) {
      return fmt::format("{}: the broker refused the login of user '{}' (return code {}: {})",
                         options.url, options.user, rc,
                         rc == kNotAuthorized ? "not authorised" : "bad user name or password");
    }
    // TLS: a broker that accepts the TCP connection but not the session refused the handshake
    // (its certificate not trusted, or no TLS there); retrying cannot help.
    if (target.tls && tcp_reachable(target.host, target.port)) {
      return fmt::format(
          "{}: TLS handshake failed (is the broker's certificate signed by the "
          "--mqtt-ca authority?): {}",
          options.url, what);
    }
    fatal = false;
    return fmt::format("{}: no connection ({})", options.url, what);
  }

  // Paho's thread on every connection (the first one too, then start-up has already said so).
  void on_connected() {
    if (connected.load()) return;
    need_birth.store(true);  // before `connected`: the thread sends nothing ahead of the birth
    connected.store(true);
  }

  // Start-up: the first connection, waited for. A refused login or TLS failure is thrown.
  void connect_first() {
    client.set_connected_handler([this](const std::string& /*cause*/) { on_connected(); });
    client.set_connection_lost_handler([this](const std::string& cause) {
      connected.store(false);
      say(fmt::format("connection to {} lost ({}); reconnecting", options.url,
                      cause.empty() ? "no reason given" : cause));
    });
    build_connect_options();
    try {
      connecting = client.connect(connect_options);
      if (connecting->wait_for(options.connect_timeout + std::chrono::seconds(1))) {
        connecting.reset();
        need_birth.store(true);
        connected.store(true);
        say(fmt::format("publishing to {}", options.url));
        return;
      }
      say(fmt::format("{}: no answer within {} ms; trying on in the background", options.url,
                      options.connect_timeout.count()));
    } catch (const mqtt::exception& e) {
      connecting.reset();
      bool fatal = false;
      const std::string why = failure(e.get_return_code(), e.what(), fatal);
      if (fatal) throw std::runtime_error(why);
      say(why + "; trying again in the background");
    }
    next_try = Steady::now() + retry;
  }

  // Called by the thread while not connected: checks the attempt under way or starts one.
  void reconnect(Steady::time_point now) {
    if (connecting) {
      if (!connecting->is_complete()) return;
      const int rc = connecting->get_return_code();
      connecting.reset();
      if (rc == 0) {  // the connected handler has run
        retry = kFirstRetry;
        return;
      }
      bool fatal = false;
      say(failure(rc, mqtt::exception::error_str(rc), fatal) + "; trying again");
      next_try = now + retry;
      retry = std::min<Steady::duration>(retry * 2, kLastRetry);
      return;
    }
    if (now < next_try || client.is_connected()) return;
    try {
      connecting = client.connect(connect_options);
    } catch (const mqtt::exception& e) {
      next_try = now + retry;
    }
  }

  void send(const MqttMessage& m) {
    if (!connected.load() || pending.pending.load() >= options.max_pending) {
      dropped.fetch_add(1);
      return;
    }
    pending.pending.fetch_add(1);
    try {
      client.publish(mqtt::make_message(m.topic, m.payload, m.qos, m.retain), nullptr, pending);
      published.fetch_add(1);
    } catch (const mqtt::exception&) {
      pending.pending.fetch_sub(1);
      dropped.fetch_add(1);
    }
  }

  // Before the thread starts (and so before the front end can start a program): the status the
  // events are reported against, and the birth.
  void prime() {
    const runtime::Status s = controller.status();
    const std::string name = program_name();
    const auto wall = MqttTopics::Clock::now();
    (void)topics.events(s, name, wall);
    if (connected.load() && need_birth.exchange(false)) {
      for (const MqttMessage& m : topics.birth(s, name, wall)) send(m);
    }
  }

  void run() {
    const auto sample_period = std::chrono::duration_cast<Steady::duration>(
        std::chrono::duration<double>(1.0 / options.sample_hz));
    auto next_sample = Steady::now();
    while (!stop.load()) {
      const auto now = Steady::now();
      if (!connected.load()) reconnect(now);
      const runtime::Status s = controller.status();
      const std::string name = program_name();
      const auto wall = MqttTopics::Clock::now();
      if (connected.load() && need_birth.exchange(false)) {
        for (const MqttMessage& m : topics.birth(s, name, wall)) send(m);
      }
      for (const MqttMessage& m : topics.events(s, name, wall)) send(m);
      if (now >= next_sample) {
        send(topics.sample(s, dropped.load(), wall));
        next_sample += sample_period;
        if (next_sample < now) next_sample = now + sample_period;
      }
      std::this_thread::sleep_until(std::min(next_sample, now + kEventPoll));
    }
  }

  // A clean goodbye: what happened since the thread's last look (a cycle that just ended), online
  // = false (retained), then disconnect; waits at most a few seconds.
  void shut_down() {
    for (const MqttMessage& m :
         topics.events(controller.status(), program_name(), MqttTopics::Clock::now())) {
      send(m);
    }
    try {
      if (connected.load()) {
        const MqttMessage m = topics.offline(false);
        client.publish(mqtt::make_message(m.topic, m.payload, m.qos, m.retain))
            ->wait_for(std::chrono::seconds(2));
      }
      if (client.is_connected()) client.disconnect()->wait_for(std::chrono::seconds(2));
    } catch (const mqtt::exception&) {
      // The broker went away meanwhile: its last will says offline.
    }
  }
};

MqttPublisher::MqttPublisher(const runtime::Controller& controller, MqttOptions options) {
  MqttTarget target = parse_mqtt_url(options.url);
  if (!(options.sample_hz > 0 && options.sample_hz <= 100)) {
    throw std::runtime_error("--mqtt-rate: the sample rate must be in (0, 100] Hz");
  }
  if (!options.ca_file.empty() && !target.tls) {
    throw std::runtime_error("--mqtt-ca: only for mqtts:// (TLS)");
  }
  impl_ = std::make_unique<Impl>(controller, std::move(options), std::move(target));
  impl_->connect_first();
  impl_->prime();
  impl_->thread = std::thread([this] { impl_->run(); });
}

MqttPublisher::~MqttPublisher() {
  impl_->stop.store(true);
  impl_->thread.join();
  impl_->shut_down();
}

void MqttPublisher::set_program(const std::string& name) {
  const std::lock_guard lock(impl_->mutex);
  impl_->program = name;
}

MqttCounters MqttPublisher::counters() const {
  return {impl_->published.load(), impl_->dropped.load(), impl_->connected.load()};
}

std::optional<std::string> MqttPublisher::take_message() {
  const std::lock_guard lock(impl_->mutex);
  if (impl_->messages.empty()) return std::nullopt;
  std::string m = std::move(impl_->messages.front());
  impl_->messages.pop_front();
  return m;
}

}  // namespace cncore::telemetry
