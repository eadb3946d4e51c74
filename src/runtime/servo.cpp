#include "runtime/servo.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <sys/mman.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <stdexcept>

namespace cncore::runtime {

static_assert(std::endian::native == std::endian::little,
              "the servo record is written in host order, which must be little-endian");

void ServoRecord::encode(std::uint8_t* out) const {
  std::memset(out, 0, kBytes);
  std::memcpy(out + 0, &kMagic, 4);
  std::memcpy(out + 4, &kVersion, 2);
  out[6] = axes;
  out[7] = state;
  std::memcpy(out + 8, &seq, 8);
  std::memcpy(out + 16, &t_ns, 8);
  std::memcpy(out + 24, &line, 4);
  out[28] = alarm;
  std::memcpy(out + 32, setpoint.data(), 8 * kMaxAxes);
}

bool ServoRecord::decode(const std::uint8_t* in) {
  std::uint32_t magic = 0;
  std::uint16_t version = 0;
  std::memcpy(&magic, in, 4);
  std::memcpy(&version, in + 4, 2);
  if (magic != kMagic || version != kVersion) return false;
  axes = in[6];
  state = in[7];
  std::memcpy(&seq, in + 8, 8);
  std::memcpy(&t_ns, in + 16, 8);
  std::memcpy(&line, in + 24, 4);
  alarm = in[28];
  std::memcpy(setpoint.data(), in + 32, 8 * kMaxAxes);
  return true;
}

SimAxes::SimAxes(const MachineConfig& machine, const AxisVec& start, const AxisVec& position_error)
    : machine_(machine), actual_(start), last_cmd_(start), error_(position_error) {}

double SimAxes::step(const AxisVec& commanded) {
  const double tau = machine_.period_s;
  const ServoConfig& s = machine_.servo;
  double worst = 0;
  for (std::size_t i = 0; i < kMaxAxes; ++i) {
    if (!machine_.axes[i].enabled) continue;
    // The loop acts on the error at the start of the period; the feed-forward on the period's
    // commanded motion (ff = 1 and no error: actual = commanded exactly).
    const double v_cmd = (commanded[i] - last_cmd_[i]) / tau;
    const double v = s.feedforward * v_cmd + s.kp_per_s * (last_cmd_[i] - actual_[i]);
    actual_[i] += v * tau;
    worst = std::max(worst, std::abs(commanded[i] - actual_[i]));
  }
  last_cmd_ = commanded;
  return worst;
}

bool SimAxes::switch_pressed(std::size_t axis) const {
  return actual_[axis] + error_[axis] >= machine_.axes[axis].max_mm;
}

void SimAxes::rebase(std::size_t axis, double delta_mm) {
  actual_[axis] += delta_mm;
  last_cmd_[axis] += delta_mm;
  error_[axis] -= delta_mm;
}

void SimAxes::reset_to(const AxisVec& position) {
  actual_ = position;
  last_cmd_ = position;
}

namespace {

class UdpOutput final : public ServoOutput {
 public:
  explicit UdpOutput(const std::string& host_port) {
    const auto colon = host_port.rfind(':');
    if (colon == std::string::npos) {
      throw std::runtime_error("--servo udp:HOST:PORT: no port in '" + host_port + "'");
    }
    std::string host = host_port.substr(0, colon);
    if (host == "localhost" || host.empty()) host = "127.0.0.1";
    const int port = std::atoi(host_port.c_str() + colon + 1);
    if (port <= 0 || port > 65535) {
      throw std::runtime_error("--servo udp:HOST:PORT: bad port in '" + host_port + "'");
    }
    addr_.sin_family = AF_INET;
    addr_.sin_port = htons(static_cast<std::uint16_t>(port));
    if (inet_pton(AF_INET, host.c_str(), &addr_.sin_addr) != 1) {
      throw std::runtime_error("--servo udp:HOST:PORT: '" + host + "' is not an IPv4 address");
    }
    fd_ = socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (fd_ < 0) throw std::runtime_error(std::string("UDP socket: ") + std::strerror(errno));
  }
  ~UdpOutput() override { close(fd_); }
  UdpOutput(const UdpOutput&) = delete;
  UdpOutput& operator=(const UdpOutput&) = delete;

  void write(const ServoRecord& record) noexcept override {
    std::uint8_t buf[ServoRecord::kBytes];
    record.encode(buf);
    const auto n = sendto(fd_, buf, sizeof buf, MSG_DONTWAIT,
                          reinterpret_cast<const sockaddr*>(&addr_), sizeof addr_);
    if (n != static_cast<ssize_t>(sizeof buf)) ++dropped_;
  }
  std::uint64_t dropped() const override { return dropped_; }

 private:
  int fd_ = -1;
  sockaddr_in addr_{};
  std::uint64_t dropped_ = 0;
};

class ShmOutput final : public ServoOutput {
 public:
  ShmOutput(const std::string& name, std::uint32_t capacity) : name_("/" + name) {
    fd_ = shm_open(name_.c_str(), O_CREAT | O_RDWR, 0600);
    if (fd_ < 0) {
      throw std::runtime_error("shm_open " + name_ + ": " + std::strerror(errno));
    }
    bytes_ = sizeof(ShmRingHeader) + std::size_t{capacity} * ServoRecord::kBytes;
    if (ftruncate(fd_, static_cast<off_t>(bytes_)) != 0) {
      const std::string why = std::strerror(errno);
      close(fd_);
      throw std::runtime_error("ftruncate " + name_ + ": " + why);
    }
    void* p = mmap(nullptr, bytes_, PROT_READ | PROT_WRITE, MAP_SHARED, fd_, 0);
    if (p == MAP_FAILED) {
      const std::string why = std::strerror(errno);
      close(fd_);
      throw std::runtime_error("mmap " + name_ + ": " + why);
    }
    base_ = static_cast<std::uint8_t*>(p);
    header_ = new (base_) ShmRingHeader{};
    header_->capacity = capacity;
    capacity_ = capacity;
  }
  ~ShmOutput() override {
    munmap(base_, bytes_);
    close(fd_);
    shm_unlink(name_.c_str());
  }
  ShmOutput(const ShmOutput&) = delete;
  ShmOutput& operator=(const ShmOutput&) = delete;

  void write(const ServoRecord& record) noexcept override {
    std::atomic_ref<std::uint64_t> count(header_->write_count);
    const std::uint64_t n = count.load(std::memory_order_relaxed);
    record.encode(base_ + sizeof(ShmRingHeader) + (n % capacity_) * ServoRecord::kBytes);
    count.store(n + 1, std::memory_order_release);
  }

 private:
  std::string name_;
  int fd_ = -1;
  std::size_t bytes_ = 0;
  std::uint8_t* base_ = nullptr;
  ShmRingHeader* header_ = nullptr;
  std::uint32_t capacity_ = 0;
};

}  // namespace

std::unique_ptr<ServoOutput> open_udp_output(const std::string& host_port) {
  return std::make_unique<UdpOutput>(host_port);
}

std::unique_ptr<ServoOutput> open_shm_output(const std::string& name, std::uint32_t capacity) {
  return std::make_unique<ShmOutput>(name, capacity);
}

}  // namespace cncore::runtime
