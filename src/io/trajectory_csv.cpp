#include "io/trajectory_csv.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <iterator>

namespace cncore::io {

namespace {

constexpr std::size_t kFlushBytes = 1 << 16;

// v with a fixed number of decimals (6 resolve 1e-6 mm). Rounds v·10^d to an integer and
// prints its digits: several times faster than a general float formatter, and a value that
// rounds to zero prints as 0.000000, never -0.000000. Huge or non-finite values fall back to fmt.
template <int Decimals>
void put_fixed(fmt::memory_buffer& b, double v) {
  constexpr std::int64_t kScale = Decimals == 6 ? 1000000 : 1000;
  static_assert(Decimals == 6 || Decimals == 3);
  if (!(std::fabs(v) < 9e12)) {
    fmt::format_to(std::back_inserter(b), "{:.{}f}", v, Decimals);
    return;
  }
  std::int64_t n = std::llround(v * static_cast<double>(kScale));
  if (n < 0) {
    b.push_back('-');
    n = -n;
  }
  const fmt::format_int whole(n / kScale);
  b.append(whole.data(), whole.data() + whole.size());
  b.push_back('.');
  char frac[Decimals];
  std::int64_t f = n % kScale;
  for (int k = Decimals - 1; k >= 0; --k) {
    frac[k] = static_cast<char>('0' + f % 10);
    f /= 10;
  }
  b.append(frac, frac + Decimals);
}

// Inactive channels (NaN) stay empty cells.
void put_optional(fmt::memory_buffer& b, double v) {
  b.push_back(',');
  if (!std::isnan(v)) put_fixed<6>(b, v);
}

}  // namespace

std::string TrajectoryCsvWriter::header(const MachineConfig& machine,
                                        const TrajectoryColumns& columns) {
  std::string h = "t,line";
  for (std::size_t i = 0; i < kMaxAxes; ++i) {
    if (!machine.axes[i].enabled) continue;
    h += ',';
    h += static_cast<char>(std::tolower(static_cast<unsigned char>(kAxisLetters[i])));
  }
  h += ",feed";
  if (columns.override_pct) h += ",override";
  if (columns.correction) h += ",correction";
  if (columns.load) h += ",load";
  if (columns.load_target) h += ",load_target";
  if (columns.ref) h += ",ref";
  if (columns.m_code) h += ",m";
  return h;
}

TrajectoryCsvWriter::TrajectoryCsvWriter(const std::string& path, const MachineConfig& machine,
                                         const TrajectoryColumns& columns)
    : file_(path), columns_(columns) {
  for (std::size_t i = 0; i < kMaxAxes; ++i) {
    if (machine.axes[i].enabled) axes_[axis_count_++] = i;
  }
  buffer_.reserve(kFlushBytes + 1024);
  const std::string h = header(machine, columns) + "\n";
  buffer_.append(h.data(), h.data() + h.size());
}

void TrajectoryCsvWriter::on_sample(const motion::Sample& s) {
  fmt::memory_buffer& b = buffer_;
  put_fixed<6>(b, s.t_s);
  b.push_back(',');
  const fmt::format_int line(s.line);
  b.append(line.data(), line.data() + line.size());
  for (std::size_t k = 0; k < axis_count_; ++k) {
    b.push_back(',');
    put_fixed<6>(b, s.position[axes_[k]]);
  }
  b.push_back(',');
  put_fixed<3>(b, s.feed_mm_min);
  if (columns_.override_pct) {
    b.push_back(',');
    put_fixed<3>(b, s.override_pct);
  }
  if (columns_.correction) put_optional(b, s.correction);
  if (columns_.load) put_optional(b, s.load_pct);
  if (columns_.load_target) put_optional(b, s.load_target_pct);
  if (columns_.ref) put_optional(b, s.ref);
  if (columns_.m_code) {
    b.push_back(',');
    if (s.aux_letter == 'M') fmt::format_to(std::back_inserter(b), "{:g}", s.aux_value);
  }
  b.push_back('\n');
  if (b.size() >= kFlushBytes) flush();
}

void TrajectoryCsvWriter::flush() {
  file_.write(std::string_view(buffer_.data(), buffer_.size()));
  buffer_.clear();
}

void TrajectoryCsvWriter::on_finish() {
  flush();
}

void TrajectoryCsvWriter::commit() {
  flush();
  file_.commit();
}

}  // namespace cncore::io
