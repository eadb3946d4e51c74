#include "io/trajectory_csv.hpp"

#include <cctype>
#include <cmath>
#include <iterator>

namespace cncore::io {

namespace {

constexpr std::size_t kFlushBytes = 1 << 16;

// Positions with 6 decimals resolve 1e-6 mm; values that round to zero print as 0 rather than
// -0.000000.
double clean(double v, double half_ulp) {
  return std::fabs(v) < half_ulp ? 0.0 : v;
}

template <typename Out>
void put_optional(Out out, double v) {
  // Inactive channels (NaN) stay empty cells.
  if (std::isnan(v)) {
    fmt::format_to(out, ",");
  } else {
    fmt::format_to(out, ",{:.6f}", clean(v, 5e-7));
  }
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
  auto out = std::back_inserter(buffer_);
  fmt::format_to(out, "{:.6f},{}", clean(s.t_s, 5e-7), s.line);
  for (std::size_t k = 0; k < axis_count_; ++k) {
    fmt::format_to(out, ",{:.6f}", clean(s.position[axes_[k]], 5e-7));
  }
  fmt::format_to(out, ",{:.3f}", clean(s.feed_mm_min, 5e-4));
  if (columns_.override_pct) fmt::format_to(out, ",{:.3f}", clean(s.override_pct, 5e-4));
  if (columns_.correction) put_optional(out, s.correction);
  if (columns_.load) put_optional(out, s.load_pct);
  if (columns_.load_target) put_optional(out, s.load_target_pct);
  buffer_.push_back('\n');
  if (buffer_.size() >= kFlushBytes) flush();
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
