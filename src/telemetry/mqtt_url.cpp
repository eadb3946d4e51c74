// `--mqtt` URLs: mqtt://HOST[:PORT]/PREFIX and mqtts://HOST[:PORT]/PREFIX.
#include <fmt/format.h>

#include <charconv>
#include <stdexcept>

#include "telemetry/telemetry.hpp"

namespace cncore::telemetry {

std::string MqttTarget::server_uri() const {
  const bool v6 = host.find(':') != std::string::npos;  // an IPv6 literal needs brackets
  return fmt::format("{}://{}{}{}:{}", tls ? "ssl" : "tcp", v6 ? "[" : "", host, v6 ? "]" : "",
                     port);
}

MqttTarget parse_mqtt_url(const std::string& url) {
  const auto bad = [&](const char* why) {
    return std::runtime_error(
        fmt::format("--mqtt {}: {} (expected mqtt://HOST:PORT/PREFIX or mqtts://…)", url, why));
  };
  MqttTarget t;
  std::string rest;
  if (url.starts_with("mqtt://")) {
    rest = url.substr(7);
    t.port = 1883;
  } else if (url.starts_with("mqtts://")) {
    rest = url.substr(8);
    t.tls = true;
    t.port = 8883;
  } else {
    throw bad("unknown scheme");
  }
  const std::size_t slash = rest.find('/');
  std::string authority = rest.substr(0, slash);
  t.prefix = slash == std::string::npos ? "" : rest.substr(slash + 1);
  while (t.prefix.ends_with('/')) t.prefix.pop_back();
  if (t.prefix.empty()) throw bad("no topic prefix");
  if (t.prefix.find_first_of("#+") != std::string::npos) throw bad("'#' or '+' in the prefix");
  std::string port;
  if (authority.starts_with('[')) {  // [IPv6]:PORT
    const std::size_t close = authority.find(']');
    if (close == std::string::npos) throw bad("unclosed '['");
    t.host = authority.substr(1, close - 1);
    if (close + 1 < authority.size()) {
      if (authority[close + 1] != ':') throw bad("expected ':' after ']'");
      port = authority.substr(close + 2);
    }
  } else {
    const std::size_t colon = authority.rfind(':');
    t.host = authority.substr(0, colon);
    if (colon != std::string::npos) port = authority.substr(colon + 1);
  }
  if (t.host.empty()) throw bad("no host");
  if (!port.empty()) {
    unsigned value = 0;
    const auto [end, ec] = std::from_chars(port.data(), port.data() + port.size(), value);
    if (ec != std::errc{} || end != port.data() + port.size() || value == 0 || value > 65535) {
      throw bad("the port must be a number from 1 to 65535");
    }
    t.port = static_cast<std::uint16_t>(value);
  }
  return t;
}

}  // namespace cncore::telemetry
