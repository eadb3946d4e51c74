#include "runtime/persist.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>

#include "core/error.hpp"

namespace cncore::runtime {

namespace {

void write_all(int fd, const std::string& data, const std::string& path) {
  std::size_t done = 0;
  while (done < data.size()) {
    const ssize_t n = ::write(fd, data.data() + done, data.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) throw std::runtime_error("cannot write " + path + ": " + std::strerror(errno));
    done += static_cast<std::size_t>(n);
  }
}

}  // namespace

std::string default_state_dir() {
  if (const char* x = std::getenv("XDG_STATE_HOME"); x != nullptr && *x != '\0') {
    return std::string(x) + "/cncore";
  }
  const char* home = std::getenv("HOME");
  return std::string(home != nullptr ? home : ".") + "/.local/state/cncore";
}

std::string state_file(const std::string& dir) {
  return dir + "/machine-state.json";
}

PersistentState load_state(const std::string& dir) {
  PersistentState s;
  const std::string path = state_file(dir);
  std::ifstream in(path, std::ios::binary);
  if (!in) return s;
  std::stringstream text;
  text << in.rdbuf();
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text.str());
    if (j.at("format").get<std::string>() != "cncore-machine-state-1") {
      throw InputError(path, 1, 1, "not a cncore machine state file (format)");
    }
    for (const auto& [k, v] : j.at("parameters").items()) s.parameters[std::stoi(k)] = v;
    if (j.contains("tools")) {
      for (const auto& t : j.at("tools")) {
        ToolEntry e;
        e.number = t.at("number");
        e.pocket = t.at("pocket");
        const auto& off = t.at("offset_mm");
        for (std::size_t i = 0; i < kMaxAxes && i < off.size(); ++i) e.offset_mm[i] = off[i];
        e.diameter_mm = t.at("diameter_mm");
        s.tools[e.number] = e;
      }
    }
    if (j.contains("position")) {
      const auto& p = j.at("position");
      for (std::size_t i = 0; i < kMaxAxes && i < p.size(); ++i) s.position[i] = p[i];
      s.has_position = true;
    }
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    throw InputError(path, 1, 1, std::string("broken machine state file: ") + e.what());
  }
  return s;
}

void save_state(const std::string& dir, const PersistentState& state) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw std::runtime_error("cannot create " + dir + ": " + ec.message());
  nlohmann::json j;
  j["format"] = "cncore-machine-state-1";
  j["parameters"] = nlohmann::json::object();
  for (const auto& [n, v] : state.parameters) j["parameters"][std::to_string(n)] = v;
  j["tools"] = nlohmann::json::array();
  for (const auto& [n, e] : state.tools) {
    j["tools"].push_back({{"number", e.number},
                          {"pocket", e.pocket},
                          {"offset_mm", e.offset_mm},
                          {"diameter_mm", e.diameter_mm}});
  }
  if (state.has_position) j["position"] = state.position.v;
  const std::string path = state_file(dir);
  const std::string temp = path + ".tmp";
  const int fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw std::runtime_error("cannot create " + temp + ": " + std::strerror(errno));
  try {
    write_all(fd, j.dump(1) + "\n", temp);
    if (::fsync(fd) != 0) throw std::runtime_error("fsync " + temp + ": " + std::strerror(errno));
  } catch (...) {
    ::close(fd);
    ::unlink(temp.c_str());
    throw;
  }
  ::close(fd);
  if (::rename(temp.c_str(), path.c_str()) != 0) {
    const std::string why = std::strerror(errno);
    ::unlink(temp.c_str());
    throw std::runtime_error("cannot rename " + temp + " to " + path + ": " + why);
  }
  // The rename itself is durable once the folder is synced.
  const int dfd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dfd >= 0) {
    ::fsync(dfd);
    ::close(dfd);
  }
}

}  // namespace cncore::runtime
