// The HTTP side of the page: routes, the token rule, the event streams and program uploads.
// cpp-httplib runs each connection on a thread of its pool; an event stream keeps its thread
// while the page is open, so their number is bounded (HttpOptions::max_viewers).
#include <fmt/format.h>
#include <httplib.h>
#include <stdlib.h>  // NOLINT(modernize-deprecated-headers): mkdtemp is POSIX

#include <algorithm>
#include <atomic>
#include <chrono>
#include <deque>
#include <filesystem>
#include <mutex>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <thread>

#include "core/error.hpp"
#include "hmi/api.hpp"
#include "hmi/hmi.hpp"
#include "hmi/program_view.hpp"
#include "hmi/web_assets.hpp"
#include "io/atomic_file.hpp"

namespace cncore::hmi {

namespace fs = std::filesystem;

bool is_loopback(const std::string& host) {
  return host == "localhost" || host == "::1" || host.starts_with("127.");
}

std::pair<std::string, std::uint16_t> split_address(const std::string& address) {
  const auto colon = address.rfind(':');
  if (colon == std::string::npos || colon == 0 || colon + 1 == address.size()) {
    throw std::runtime_error("--http " + address + ": expected HOST:PORT (e.g. 127.0.0.1:8080)");
  }
  std::string host = address.substr(0, colon);
  if (host.size() > 2 && host.front() == '[' && host.back() == ']') {
    host = host.substr(1, host.size() - 2);
  }
  const std::string port_text = address.substr(colon + 1);
  char* end = nullptr;
  const long port = std::strtol(port_text.c_str(), &end, 10);
  if (*end != '\0' || port < 0 || port > 65535) {
    throw std::runtime_error("--http " + address + ": '" + port_text + "' is not a port");
  }
  return {host, static_cast<std::uint16_t>(port)};
}

namespace {

// Compares without stopping at the first difference (no timing hint of how much matched).
bool same_secret(std::string_view a, std::string_view b) {
  unsigned diff = a.size() == b.size() ? 0U : 1U;
  for (std::size_t i = 0; i < a.size(); ++i) {
    diff |= static_cast<unsigned>(a[i] ^ (i < b.size() ? b[i] : 0));
  }
  return diff == 0;
}

// A program name for the upload folder: its last path component, letters, digits and ._- only.
std::string safe_name(std::string name) {
  const auto slash = name.find_last_of("/\\");
  if (slash != std::string::npos) name = name.substr(slash + 1);
  for (char& ch : name) {
    const bool ok =
        std::isalnum(static_cast<unsigned char>(ch)) != 0 || ch == '.' || ch == '_' || ch == '-';
    if (!ok) ch = '_';
  }
  if (name.empty() || name.front() == '.') name = "program.ngc";
  return name;
}

// cpp-httplib (as Debian builds it) compresses "application/json" and text/* answers with Brotli
// at its highest quality when the browser accepts it: seconds for a path of a few MB. This type
// (the same with its charset) is sent as it is.
constexpr const char* kJson = "application/json; charset=utf-8";

void send(httplib::Response& res, const Reply& r) {
  res.status = r.http_status;
  res.set_content(r.body, kJson);
}

}  // namespace

struct HttpServer::Impl {
  runtime::Controller& controller;
  HttpOptions options;
  std::string host;
  std::uint16_t port = 0;
  httplib::Server server;
  std::thread thread;
  std::atomic<bool> stopping{false};
  std::atomic<std::size_t> viewers{0};
  std::string upload_dir;
  bool own_upload_dir = false;
  const std::chrono::steady_clock::time_point t0 = std::chrono::steady_clock::now();

  std::mutex mutex;  // guards view, program_serial, messages, last_limits, machine_serial
  std::shared_ptr<const ProgramView> view = std::make_shared<ProgramView>();
  std::uint64_t program_serial = 0;
  std::deque<std::pair<std::uint64_t, std::string>> messages;  // the last few, with ids
  std::uint64_t message_serial = 0;
  runtime::MachineLimits last_limits = controller.limits();
  std::uint64_t machine_serial = 0;  // changes of the limits (the travel) since the start

  Impl(runtime::Controller& c, HttpOptions o) : controller(c), options(std::move(o)) {}

  bool authorized(const httplib::Request& req) const {
    if (options.token.empty()) return true;
    const std::string h = req.get_header_value("Authorization");
    constexpr std::string_view kBearer = "Bearer ";
    return h.starts_with(kBearer) &&
           same_secret(std::string_view(h).substr(kBearer.size()), options.token);
  }

  // A control must come from the page itself: a JSON (or program text) body with the token, and
  // no Origin header naming another site (a page elsewhere that the operator has open cannot
  // post to the machine through the operator's browser).
  std::optional<Reply> refuse_post(const httplib::Request& req) const {
    if (!authorized(req)) {
      return Reply{403,
                   "{\"ok\":false,\"error\":\"this control needs the token (read-only viewer)\"}"};
    }
    const std::string origin = req.get_header_value("Origin");
    const std::string host_header = req.get_header_value("Host");
    if (!origin.empty() && origin != "http://" + host_header) {
      return Reply{403, R"({"ok":false,"error":"a control from a page of another site"})"};
    }
    return std::nullopt;
  }

  void set_view(std::shared_ptr<const ProgramView> v) {
    const std::lock_guard lock(mutex);
    view = std::move(v);
    ++program_serial;
  }

  Reply load(const std::string& path, const std::string& name) {
    const runtime::Result r = controller.load_program(path);
    if (!r.ok) return reply_of(r);
    try {
      set_view(std::make_shared<ProgramView>(path, name, controller.machine(),
                                             controller.status().work_offset));
    } catch (const std::exception& e) {
      post_message(std::string("the program's path cannot be drawn: ") + e.what());
      set_view(std::make_shared<ProgramView>());
    }
    return reply_of(r);
  }

  Reply upload(const httplib::Request& req) {
    const std::string name = safe_name(req.get_param_value("name"));
    const std::string path = (fs::path(upload_dir) / name).string();
    try {
      io::AtomicOutputFile out(path);
      out.write(req.body);
      out.commit();
    } catch (const InputError& e) {
      return reply_of(runtime::Result::fail(e.what()));
    }
    return load(path, name);
  }

  void post_message(const std::string& text) {
    const std::lock_guard lock(mutex);
    messages.emplace_back(++message_serial, text);
    while (messages.size() > 16) messages.pop_front();
  }

  // One event: {"status":{…},"program_serial":N,"messages":[[id,"text"],…]} with the messages
  // newer than `seen`.
  std::string event(std::uint64_t& seen) {
    const runtime::Status s = controller.status();
    std::shared_ptr<const ProgramView> v;
    nlohmann::json fresh = nlohmann::json::array();
    std::uint64_t serial = 0;
    {
      const std::lock_guard lock(mutex);
      v = view;
      serial = program_serial;
      for (const auto& [id, text] : messages) {
        if (id > seen) fresh.push_back({id, text});
      }
      seen = message_serial;
    }
    // The travel a sender may have written ($130…): the page fetches /api/machine again when
    // machine_serial changes.
    const runtime::MachineLimits limits = controller.limits();
    std::uint64_t travel_serial = 0;
    {
      const std::lock_guard lock(mutex);
      if (limits != last_limits) {
        last_limits = limits;
        ++machine_serial;
      }
      travel_serial = machine_serial;
    }
    const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return fmt::format(
        R"(data: {{"status":{},"program_serial":{},"heightmap_version":{},"machine_serial":{},)"
        R"("messages":{}}})"
        "\n\n",
        status_event_json(s, controller.machine(), v.get(), t), serial, s.heightmap_version,
        travel_serial, fresh.dump());
  }

  void events(httplib::Response& res) {
    if (viewers.fetch_add(1) >= options.max_viewers) {
      viewers.fetch_sub(1);
      send(res, {503, R"({"ok":false,"error":"too many viewers"})"});
      return;
    }
    res.set_header("Cache-Control", "no-cache");
    const auto period = std::chrono::duration_cast<std::chrono::steady_clock::duration>(
        std::chrono::duration<double>(1.0 / std::max(options.status_hz, 1.0)));
    auto seen = std::make_shared<std::uint64_t>(0);
    auto next =
        std::make_shared<std::chrono::steady_clock::time_point>(std::chrono::steady_clock::now());
    res.set_chunked_content_provider(
        "text/event-stream",
        [this, period, seen, next](std::size_t /*offset*/, httplib::DataSink& sink) {
          std::this_thread::sleep_until(*next);
          *next = std::max(*next + period, std::chrono::steady_clock::now());
          if (stopping.load()) return false;
          const std::string e = event(*seen);
          return sink.write(e.data(), e.size());
        },
        [this](bool /*success*/) { viewers.fetch_sub(1); });
  }

  void session(const httplib::Request& req, httplib::Response& res) const {
    const nlohmann::json j{{"token_required", !options.token.empty()},
                           {"authorized", authorized(req)}};
    res.set_content(j.dump(), kJson);
  }

  void routes() {
    server.Get("/api/events",
               [this](const httplib::Request&, httplib::Response& res) { events(res); });
    server.Get("/api/session",
               [this](const httplib::Request& req, httplib::Response& res) { session(req, res); });
    server.Get("/api/machine", [this](const httplib::Request&, httplib::Response& res) {
      MachineConfig m = controller.machine();
      runtime::apply_limits(m, controller.limits());  // the travel and speeds as they are now
      res.set_content(machine_json(m), kJson);
    });
    server.Get("/api/program", [this](const httplib::Request&, httplib::Response& res) {
      std::shared_ptr<const ProgramView> v;
      {
        const std::lock_guard lock(mutex);
        v = view;
      }
      res.set_content(v->json(), kJson);
    });
    server.Get("/api/heightmap", [this](const httplib::Request&, httplib::Response& res) {
      const auto map = controller.heightmap();
      if (!map) {
        return send(res, {404, R"({"ok":false,"error":"the machine has no [stock]"})"});
      }
      res.set_header("X-Heightmap-Version", std::to_string(map->version));
      res.set_header("Cache-Control", "no-cache");
      res.set_content(heightmap_binary(*map), "application/octet-stream");
    });
    server.Post("/api/program", [this](const httplib::Request& req, httplib::Response& res) {
      if (auto refused = refuse_post(req)) return send(res, *refused);
      send(res, upload(req));
    });
    server.Post("/api/load", [this](const httplib::Request& req, httplib::Response& res) {
      if (auto refused = refuse_post(req)) return send(res, *refused);
      const auto j = nlohmann::json::parse(req.body, nullptr, false);
      if (!j.is_object() || !j.contains("path") || !j["path"].is_string()) {
        return send(res, bad_request("load: give {\"path\": FILE}"));
      }
      const std::string path = j["path"];
      send(res, load(path, fs::path(path).filename().string()));
    });
    server.Post(R"(/api/([a-z-]+))", [this](const httplib::Request& req, httplib::Response& res) {
      if (auto refused = refuse_post(req)) return send(res, *refused);
      send(res, control(controller, req.matches[1].str(), req.body));
    });
    server.Get(R"(/.*)", [](const httplib::Request& req, httplib::Response& res) {
      const WebAsset* a = find_web_asset(req.path);
      if (a == nullptr) {
        res.status = 404;
        res.set_content("not found\n", "text/plain");
        return;
      }
      res.set_content(std::string(a->bytes), std::string(a->content_type));
    });
  }

  void make_upload_dir() {
    if (!options.upload_dir.empty()) {
      upload_dir = options.upload_dir;
      fs::create_directories(upload_dir);
      return;
    }
    std::string tmpl = (fs::temp_directory_path() / "cncore-hmi-XXXXXX").string();
    if (::mkdtemp(tmpl.data()) == nullptr) {
      throw std::runtime_error("--http: cannot make a folder for uploaded programs in " +
                               fs::temp_directory_path().string());
    }
    upload_dir = tmpl;
    own_upload_dir = true;
  }
};

HttpServer::HttpServer(runtime::Controller& controller, HttpOptions options)
    : impl_(std::make_unique<Impl>(controller, std::move(options))) {
  Impl& m = *impl_;
  auto [host, port] = split_address(m.options.address);
  if (!is_loopback(host) && m.options.token.empty()) {
    throw std::runtime_error("--http " + m.options.address +
                             ": not a loopback address; give --http-token or --http-token-file "
                             "so that only the operator can control the machine");
  }
  m.host = host;
  m.make_upload_dir();
  // Event streams hold a thread each; the rest serve requests.
  const std::size_t threads = m.options.max_viewers + 4;
  m.server.new_task_queue = [threads] { return new httplib::ThreadPool(threads); };
  m.server.set_keep_alive_timeout(2);
  m.server.set_payload_max_length(ProgramView::kMaxTextBytes);
  m.routes();
  if (port == 0) {
    const int bound = m.server.bind_to_any_port(host);
    if (bound <= 0) throw std::runtime_error("--http " + m.options.address + ": cannot listen");
    m.port = static_cast<std::uint16_t>(bound);
  } else {
    if (!m.server.bind_to_port(host, port)) {
      throw std::runtime_error("--http " + m.options.address +
                               ": cannot listen (address in use or not on this machine)");
    }
    m.port = port;
  }
  m.thread = std::thread([&m] { m.server.listen_after_bind(); });
}

HttpServer::~HttpServer() {
  impl_->stopping.store(true);
  impl_->server.stop();
  if (impl_->thread.joinable()) impl_->thread.join();
  if (impl_->own_upload_dir) {
    std::error_code ec;
    fs::remove_all(impl_->upload_dir, ec);
  }
}

std::uint16_t HttpServer::port() const {
  return impl_->port;
}

std::string HttpServer::url() const {
  const std::string& h = impl_->host;
  return fmt::format("http://{}:{}/", h.find(':') == std::string::npos ? h : "[" + h + "]",
                     impl_->port);
}

void HttpServer::program_loaded(const std::string& path) {
  try {
    impl_->set_view(std::make_shared<ProgramView>(path, fs::path(path).filename().string(),
                                                  impl_->controller.machine(),
                                                  impl_->controller.status().work_offset));
  } catch (const std::exception& e) {
    impl_->post_message(std::string("the program's path cannot be drawn: ") + e.what());
  }
}

void HttpServer::post_message(const std::string& text) {
  impl_->post_message(text);
}

}  // namespace cncore::hmi
