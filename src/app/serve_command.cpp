// `cncore serve`: the controller process (src/runtime) with its text console on standard input
// and, when asked, the Grbl 1.1 endpoints (src/grbl) for senders, the operator's web page
// (src/hmi) and the telemetry publishers (src/telemetry: MTConnect SHDR, MQTT).
#include <poll.h>
#include <unistd.h>

#include <atomic>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "app/cli_common.hpp"
#include "app/commands.hpp"
#include "app/serve_console.hpp"
#include "grbl/endpoint.hpp"
#include "hmi/hmi.hpp"
#include "io/trajectory_csv.hpp"
#include "runtime/control.hpp"
#include "runtime/persist.hpp"
#include "telemetry/telemetry.hpp"

namespace cncore::app {

namespace {

std::atomic<bool> g_stop{false};

extern "C" void on_stop_signal(int /*sig*/) {
  g_stop.store(true);
}

void install_stop_handlers() {
  struct sigaction sa {};
  sa.sa_handler = on_stop_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = 0;  // no SA_RESTART: poll() returns at once
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

runtime::ControllerOptions controller_options(const ServeArgs& a) {
  runtime::ControllerOptions o;
  o.subroutine_path = a.subroutine_path;
  if (a.servo == "sim") {
    o.servo = runtime::ServoKind::kSim;
  } else if (a.servo.starts_with("udp:")) {
    o.servo = runtime::ServoKind::kUdp;
    o.servo_address = a.servo.substr(4);
  } else if (a.servo.starts_with("shm:") && a.servo.size() > 4) {
    o.servo = runtime::ServoKind::kShm;
    o.servo_address = a.servo.substr(4);
  } else {
    throw UsageError("--servo " + a.servo + ": expected sim, udp:HOST:PORT or shm:NAME");
  }
  o.state_dir =
      a.no_state ? "" : (a.state_dir.empty() ? runtime::default_state_dir() : a.state_dir);
  o.realtime = !a.no_realtime;
  o.sample_ring = a.trajectory.empty() ? 0 : std::size_t{1} << 16;
  return o;
}

// Writes the served cycles to a trajectory file while the controller runs (its own thread).
class TrajectoryRecorder {
 public:
  TrajectoryRecorder(runtime::Controller& c, const std::string& path)
      : controller_(c), writer_(path, c.machine(), columns(c.machine())) {
    thread_ = std::thread([this] { run(); });
  }
  ~TrajectoryRecorder() {
    if (thread_.joinable()) finish();
  }
  TrajectoryRecorder(const TrajectoryRecorder&) = delete;
  TrajectoryRecorder& operator=(const TrajectoryRecorder&) = delete;
  void finish() {
    stop_.store(true);
    thread_.join();
    drain();
    writer_.on_finish();
    writer_.commit();
  }

 private:
  // The override; the spindle load when the machine has a cutting simulation ([stock]).
  static io::TrajectoryColumns columns(const MachineConfig& m) {
    io::TrajectoryColumns cols;
    cols.override_pct = true;
    cols.load = m.cutting.stock.enabled;
    return cols;
  }
  void drain() {
    while (true) {
      const std::size_t n = controller_.read_samples(batch_);
      for (std::size_t i = 0; i < n; ++i) writer_.on_sample(batch_[i]);
      if (n < batch_.size()) return;
    }
  }
  void run() {
    while (!stop_.load()) {
      drain();
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  }
  runtime::Controller& controller_;
  io::TrajectoryCsvWriter writer_;
  std::vector<motion::Sample> batch_ = std::vector<motion::Sample>(1024);
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

// The Grbl settings: the machine's values, overridden by those a sender wrote before (grbl.json
// in the state folder); they are put into the machine before the controller starts.
void load_grbl_settings(grbl::SettingsStore& store, MachineConfig& machine,
                        const std::string& state_dir) {
  store.settings = grbl::Settings::from_machine(machine);
  store.defaults = store.settings;
  if (state_dir.empty()) return;
  std::filesystem::create_directories(state_dir);
  store.path = state_dir + "/grbl.json";
  std::ifstream f(store.path);
  if (!f) return;
  std::stringstream text;
  text << f.rdbuf();
  store.settings.merge_json(text.str());
  store.settings.apply(machine);
}

// The first line of --mqtt-password-file (a password kept out of the command line and `ps`).
std::string read_password(const std::string& path) {
  require_readable(path, "--mqtt-password-file");
  std::ifstream f(path);
  std::string line;
  std::getline(f, line);
  if (!line.empty() && line.back() == '\r') line.pop_back();
  return line;
}

std::unique_ptr<telemetry::MqttPublisher> start_mqtt(const runtime::Controller& c,
                                                     const ServeArgs& a) {
  telemetry::MqttOptions o;
  o.url = a.mqtt;
  o.user = a.mqtt_user;
  if (!a.mqtt_password_file.empty()) o.password = read_password(a.mqtt_password_file);
  if (!a.mqtt_ca.empty()) require_readable(a.mqtt_ca, "--mqtt-ca");
  o.ca_file = a.mqtt_ca;
  o.sample_hz = a.mqtt_rate_hz;
  o.program = a.program;
  try {
    return std::make_unique<telemetry::MqttPublisher>(c, o);
  } catch (const std::runtime_error& e) {
    throw UsageError(e.what());
  }
}

// The front ends that show the controller's messages besides the console.
struct FrontEnds {
  hmi::HttpServer* web = nullptr;
  telemetry::MqttPublisher* mqtt = nullptr;
  telemetry::ShdrAdapter* shdr = nullptr;
};

// The controller's messages (and the MQTT publisher's) go to the console and to the web page.
void print_messages(runtime::Controller& c, const FrontEnds& f) {
  while (auto m = c.take_message()) {
    std::cout << "msg: " << *m << "\n";
    if (f.web != nullptr) f.web->post_message(*m);
  }
  while (auto m = f.mqtt != nullptr ? f.mqtt->take_message() : std::nullopt) {
    std::cout << "msg: " << *m << "\n";
  }
  std::cout.flush();
}

// --http-token, or the first line of --http-token-file (surrounding blanks dropped).
std::string http_token(const ServeArgs& a) {
  if (a.http_token_file.empty()) return a.http_token;
  require_readable(a.http_token_file);
  std::ifstream f(a.http_token_file);
  std::string line;
  std::getline(f, line);
  const auto first = line.find_first_not_of(" \t\r");
  const auto last = line.find_last_not_of(" \t\r");
  if (first == std::string::npos) {
    throw UsageError("--http-token-file " + a.http_token_file + ": the file holds no token");
  }
  return line.substr(first, last - first + 1);
}

// The console on standard input until `quit`, SIGINT or SIGTERM (at the end of standard input it
// runs on as a daemon).
void run_console(runtime::Controller& controller, const FrontEnds& f) {
  bool stdin_open = true;
  bool quit = false;
  std::string pending;
  while (!g_stop.load() && !quit) {
    pollfd p{STDIN_FILENO, POLLIN, 0};
    const int rc = stdin_open ? ::poll(&p, 1, 100) : (::usleep(100000), 0);
    if (rc > 0) {
      char buf[4096];
      const ssize_t n = ::read(STDIN_FILENO, buf, sizeof buf);
      if (n <= 0) {
        stdin_open = false;  // a daemon: runs on until SIGINT / SIGTERM
      } else {
        pending.append(buf, static_cast<std::size_t>(n));
      }
      for (auto nl = pending.find('\n'); nl != std::string::npos && !quit;
           nl = pending.find('\n')) {
        const std::string line = pending.substr(0, nl);
        pending.erase(0, nl + 1);
        const std::string answer = console_command(controller, line, quit);
        // A program loaded from the console: the web page draws it, telemetry names it.
        if (answer == "ok" && line.starts_with("load ")) {
          std::istringstream words(line.substr(5));
          std::string path;
          words >> path;
          if (f.web != nullptr) f.web->program_loaded(path);
          if (f.mqtt != nullptr) f.mqtt->set_program(path);
          if (f.shdr != nullptr) f.shdr->set_program(path);
        }
        if (!answer.empty()) std::cout << answer << "\n";
        std::cout.flush();
      }
    }
    print_messages(controller, f);
  }
}

// --http: the web page, or a usage error (address, token rule, bind).
std::unique_ptr<hmi::HttpServer> start_web(runtime::Controller& controller, const ServeArgs& a,
                                           const std::string& token) {
  if (a.http.empty()) return nullptr;
  try {
    hmi::HttpOptions o;
    o.address = a.http;
    o.token = token;
    return std::make_unique<hmi::HttpServer>(controller, o);
  } catch (const std::runtime_error& e) {
    throw UsageError(e.what());
  }
}

}  // namespace

int command_serve(const ServeArgs& a) {
  if (a.http.empty() && (!a.http_token.empty() || !a.http_token_file.empty())) {
    throw UsageError("--http-token and --http-token-file go with --http");
  }
  const std::string token = a.http.empty() ? "" : http_token(a);
  MachineConfig machine = machine_from(a.machine);
  const runtime::ControllerOptions options = controller_options(a);
  if (!a.program.empty()) require_readable(a.program);
  grbl::SharedSettings grbl_settings;
  const bool grbl = !a.grbl_tcp.empty() || !a.grbl_pty.empty();
  if (grbl) load_grbl_settings(grbl_settings.store, machine, options.state_dir);
  install_stop_handlers();
  runtime::Controller controller(machine, options);
  std::unique_ptr<TrajectoryRecorder> recorder;
  if (!a.trajectory.empty()) {
    recorder = std::make_unique<TrajectoryRecorder>(controller, a.trajectory);
  }
  // Telemetry reads the controller only; destroyed before it.
  std::optional<telemetry::ShdrAdapter> shdr;
  if (!a.mtconnect.empty()) {
    try {
      shdr.emplace(controller, telemetry::ShdrOptions{a.mtconnect});
    } catch (const std::runtime_error& e) {
      throw UsageError(e.what());
    }
    shdr->set_program(a.program);
    std::cout << "mtconnect SHDR on port " << shdr->port() << "\n";
  }
  std::unique_ptr<telemetry::MqttPublisher> mqtt;
  if (!a.mqtt.empty()) mqtt = start_mqtt(controller, a);
  std::vector<std::unique_ptr<grbl::Endpoint>> endpoints;
  try {
    if (!a.grbl_tcp.empty()) {
      endpoints.push_back(grbl::Endpoint::tcp(controller, grbl_settings, a.grbl_tcp));
    }
    if (!a.grbl_pty.empty()) {
      endpoints.push_back(grbl::Endpoint::pty(controller, grbl_settings, a.grbl_pty));
    }
  } catch (const std::runtime_error& e) {
    throw UsageError(e.what());
  }
  std::unique_ptr<hmi::HttpServer> web = start_web(controller, a, token);
  std::cout << "cncore serve: " << machine.name << ", period " << machine.period_s * 1000
            << " ms, servo " << a.servo << "; commands on stdin\n";
  for (const auto& e : endpoints) std::cout << e->description() << "\n";
  if (web) {
    std::cout << "web page on " << web->url() << (token.empty() ? "" : " (token set)") << "\n";
  }
  if (!a.program.empty()) {
    const runtime::Result r = controller.load_program(a.program);
    if (!r.ok) throw UsageError("--program: " + r.error);
    if (web) web->program_loaded(a.program);
    if (a.start) {
      const runtime::Result s = controller.cycle_start();
      if (!s.ok) throw UsageError("--start: " + s.error);
    }
  }
  const FrontEnds front{web.get(), mqtt.get(), shdr ? &*shdr : nullptr};
  print_messages(controller, front);
  run_console(controller, front);
  endpoints.clear();  // no sender acts during the stop
  web.reset();
  if (recorder) {
    // The controlled stop happens in the controller's destructor; record it too.
    controller.reset();
    for (int i = 0; i < 60000; ++i) {
      const runtime::MachineState s = controller.status().state;
      if (s != runtime::MachineState::kRun && s != runtime::MachineState::kHold &&
          s != runtime::MachineState::kJog && s != runtime::MachineState::kHoming) {
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    recorder->finish();
  }
  return 0;
}

}  // namespace cncore::app
