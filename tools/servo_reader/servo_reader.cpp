// cncore-servo-reader: receives the set-points `cncore serve --servo udp:…|shm:…` sends and says
// what arrived: every record in order, gaps, duplicates, and the intervals between arrivals as a
// histogram (the wire format: src/runtime/servo.hpp, docs/runtime.md).
//
//   cncore-servo-reader udp:PORT [--seconds S] [--print N]
//   cncore-servo-reader shm:NAME [--seconds S] [--print N]
#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <sys/mman.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <string>
#include <thread>

#include "runtime/pacing.hpp"
#include "runtime/servo.hpp"

namespace {

using cncore::runtime::ServoRecord;

struct Tally {
  std::uint64_t records = 0, gaps = 0, missing = 0, duplicates = 0, out_of_order = 0;
  std::uint64_t first = 0, last = 0;
  bool any = false;
  std::int64_t last_arrival_ns = 0;
  cncore::runtime::Histogram intervals{100000};
  int print = 0;

  void add(const ServoRecord& r) {
    const std::int64_t now = cncore::runtime::monotonic_ns();
    if (print > 0) {
      --print;
      std::printf("seq %llu t %.6f s state %u line %u X %.6f Y %.6f Z %.6f\n",
                  static_cast<unsigned long long>(r.seq), static_cast<double>(r.t_ns) * 1e-9,
                  r.state, r.line, r.setpoint[0], r.setpoint[1], r.setpoint[2]);
    }
    ++records;
    if (!any) {
      first = last = r.seq;
      any = true;
      last_arrival_ns = now;
      return;
    }
    intervals.add_ns(now - last_arrival_ns);
    last_arrival_ns = now;
    if (r.seq == last) {
      ++duplicates;
    } else if (r.seq < last) {
      ++out_of_order;
    } else {
      if (r.seq != last + 1) {
        ++gaps;
        missing += r.seq - last - 1;
      }
      last = r.seq;
    }
  }

  void report() const {
    std::printf(
        "records %llu first %llu last %llu gaps %llu missing %llu duplicates %llu "
        "out_of_order %llu\n",
        static_cast<unsigned long long>(records), static_cast<unsigned long long>(first),
        static_cast<unsigned long long>(last), static_cast<unsigned long long>(gaps),
        static_cast<unsigned long long>(missing), static_cast<unsigned long long>(duplicates),
        static_cast<unsigned long long>(out_of_order));
    std::printf("interval_us p50 %.0f p99 %.0f p99.9 %.0f max %.0f\n", intervals.quantile_us(0.5),
                intervals.quantile_us(0.99), intervals.quantile_us(0.999), intervals.max_us());
  }
};

int read_udp(int port, double seconds, Tally& t) {
  const int fd = socket(AF_INET, SOCK_DGRAM, 0);
  int size = 8 << 20;
  setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &size, sizeof size);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<std::uint16_t>(port));
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
    std::fprintf(stderr, "cncore-servo-reader: bind 127.0.0.1:%d: %s\n", port,
                 std::strerror(errno));
    return 1;
  }
  timeval tv{0, 100000};
  setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  std::printf("listening on udp 127.0.0.1:%d\n", port);
  std::fflush(stdout);
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  std::uint8_t buf[256];
  while (std::chrono::steady_clock::now() < end) {
    const ssize_t n = recv(fd, buf, sizeof buf, 0);
    ServoRecord r;
    if (n == static_cast<ssize_t>(ServoRecord::kBytes) && r.decode(buf)) t.add(r);
  }
  close(fd);
  return 0;
}

int read_shm(const std::string& name, double seconds, Tally& t) {
  const std::string path = "/" + name;
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  int fd = -1;
  while (fd < 0 && std::chrono::steady_clock::now() < end) {
    fd = shm_open(path.c_str(), O_RDONLY, 0);
    if (fd < 0) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  if (fd < 0) {
    std::fprintf(stderr, "cncore-servo-reader: no shared memory %s\n", path.c_str());
    return 1;
  }
  cncore::runtime::ShmRingHeader h;
  while (read(fd, &h, sizeof h) != static_cast<ssize_t>(sizeof h) || h.capacity == 0) {
    lseek(fd, 0, SEEK_SET);
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  const std::size_t bytes = sizeof h + std::size_t{h.capacity} * ServoRecord::kBytes;
  void* p = mmap(nullptr, bytes, PROT_READ, MAP_SHARED, fd, 0);
  const auto* base = static_cast<std::uint8_t*>(p);
  auto* header = const_cast<cncore::runtime::ShmRingHeader*>(
      reinterpret_cast<const cncore::runtime::ShmRingHeader*>(base));
  std::atomic_ref<std::uint64_t> count(header->write_count);
  std::uint64_t next = count.load(std::memory_order_acquire);
  while (std::chrono::steady_clock::now() < end) {
    const std::uint64_t written = count.load(std::memory_order_acquire);
    if (written - next > h.capacity) next = written - h.capacity;  // fell behind: lost records
    for (; next < written; ++next) {
      ServoRecord r;
      if (r.decode(base + sizeof h + (next % h.capacity) * ServoRecord::kBytes)) t.add(r);
    }
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  munmap(p, bytes);
  close(fd);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr,
                 "usage: cncore-servo-reader udp:PORT|shm:NAME [--seconds S] [--print N]\n");
    return 2;
  }
  const std::string where = argv[1];
  double seconds = 10;
  Tally t;
  for (int i = 2; i + 1 < argc; i += 2) {
    const std::string opt = argv[i];
    if (opt == "--seconds") {
      seconds = std::atof(argv[i + 1]);
    } else if (opt == "--print") {
      t.print = std::atoi(argv[i + 1]);
    } else {
      std::fprintf(stderr, "cncore-servo-reader: unknown option %s\n", opt.c_str());
      return 2;
    }
  }
  int rc = 2;
  if (where.starts_with("udp:")) rc = read_udp(std::atoi(where.c_str() + 4), seconds, t);
  if (where.starts_with("shm:")) rc = read_shm(where.substr(4), seconds, t);
  if (rc == 2) std::fprintf(stderr, "cncore-servo-reader: expected udp:PORT or shm:NAME\n");
  if (rc == 0) t.report();
  return rc;
}
