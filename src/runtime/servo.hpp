// The servo side of the cycle: the simulated axes (a position loop with a following error and
// the homing switches) and where each cycle's set-points are also sent (a UDP datagram, a
// shared-memory ring a co-process reads). The record layout is the contract with those
// readers (docs/runtime.md, tools/servo_reader.cpp).
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>

#include "config/machine_config.hpp"
#include "core/geometry.hpp"

namespace cncore::runtime {

// One cycle's set-points: 80 bytes, little-endian, no padding on the wire.
struct ServoRecord {
  static constexpr std::uint32_t kMagic = 0x53434e43;  // "CNCS" as bytes C N C S
  static constexpr std::uint16_t kVersion = 1;
  static constexpr std::size_t kBytes = 80;
  std::uint64_t seq = 0;   // cycle number since the controller started, +1 every cycle
  std::uint64_t t_ns = 0;  // seq · period
  std::uint8_t axes = 0;   // bit per axis slot X Y Z A B C that the machine has
  std::uint8_t state = 0;  // runtime::MachineState
  std::uint8_t alarm = 0;  // runtime::AlarmCode
  std::uint32_t line = 0;  // program line under the tool
  std::array<double, kMaxAxes> setpoint{};  // mm or deg, machine coordinates

  void encode(std::uint8_t* out) const;  // kBytes
  // False when the magic or version differs.
  bool decode(const std::uint8_t* in);
};

// Shared-memory ring (POSIX shm, /dev/shm/NAME): a header and `capacity` records. The writer
// stores record n in slot n mod capacity, then publishes write_count = n + 1 (release). A
// reader that falls more than `capacity` records behind has lost records (it can tell: it
// compares its position with write_count before and after copying a slot).
struct ShmRingHeader {
  static constexpr std::uint32_t kMagic = 0x52434e43;  // "CNCR"
  std::uint32_t magic = kMagic;
  std::uint16_t version = 1;
  std::uint16_t record_bytes = ServoRecord::kBytes;
  std::uint32_t capacity = 0;
  std::uint32_t reserved = 0;
  std::uint64_t write_count = 0;  // accessed through std::atomic_ref
};

// The simulated axes: per axis, velocity = ff·(commanded velocity over the period) + kp·(the
// error at its start), integrated every period. Switches sit at each axis's travel maximum in the
// axes' true position, which differs from the controller's by `position_error` until homing finds
// it.
class SimAxes {
 public:
  SimAxes(const MachineConfig& machine, const AxisVec& start, const AxisVec& position_error);
  // One period with these set-points; returns the largest |commanded − actual| over the axes.
  double step(const AxisVec& commanded);
  const AxisVec& actual() const { return actual_; }
  bool switch_pressed(std::size_t axis) const;
  // Homing latched: the controller's coordinate of `axis` moves by delta (the axis itself stays).
  void rebase(std::size_t axis, double delta_mm);
  // Set-points jump (a new start: E-stop cleared, state restored): actual follows at once.
  void reset_to(const AxisVec& position);

 private:
  const MachineConfig& machine_;
  AxisVec actual_, last_cmd_, error_;
};

// Where set-points go besides the simulated axes. write() runs in the cycle: no allocation, no
// blocking (a datagram that cannot be sent at once is dropped and counted).
class ServoOutput {
 public:
  virtual ~ServoOutput() = default;
  virtual void write(const ServoRecord& record) noexcept = 0;
  virtual std::uint64_t dropped() const { return 0; }
};

// "udp:HOST:PORT" (numeric IPv4 or localhost) or "shm:NAME"; throws std::runtime_error.
std::unique_ptr<ServoOutput> open_udp_output(const std::string& host_port);
std::unique_ptr<ServoOutput> open_shm_output(const std::string& name, std::uint32_t capacity);

}  // namespace cncore::runtime
