// Reference-value analysis (SFT / SFTCAN), validation against the machine, limit check and
// the effective-table listing.
#include "tables/analysis.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/error.hpp"

namespace cncore::tables::detail {

double value_of_signal(const Values& values, int number, double t_s, bool& found) {
  double v = 0;
  found = false;
  if (auto it = values.signals.find(number); it != values.signals.end()) {
    v = it->second;
    found = true;
  }
  // The latest change at or before t_s wins (changes are few; scanned in time order).
  double latest_t = -1;
  for (const SignalChange& c : values.signal_changes) {
    if (c.number == number && c.t_s <= t_s + 1e-12 && c.t_s >= latest_t) {
      v = c.value;
      latest_t = c.t_s;
      found = true;
    }
  }
  return v;
}

SegmentExtremes hermite_extremes(double p0, double p1, double m0, double m1, double h) {
  // In u: p'(u) = (6u²−6u)p0 + (3u²−4u+1)h m0 + (−6u²+6u)p1 + (3u²−2u)h m1
  //       p''(u) = (12u−6)p0 + (6u−4)h m0 + (−12u+6)p1 + (6u−2)h m1
  auto d1 = [&](double u) {
    return (6 * u * u - 6 * u) * p0 + (3 * u * u - 4 * u + 1) * h * m0 + (-6 * u * u + 6 * u) * p1 +
           (3 * u * u - 2 * u) * h * m1;
  };
  auto d2 = [&](double u) {
    return (12 * u - 6) * p0 + (6 * u - 4) * h * m0 + (-12 * u + 6) * p1 + (6 * u - 2) * h * m1;
  };
  double a0 = d2(0), a1 = d2(1);
  double best = std::max(std::abs(d1(0)), std::abs(d1(1)));
  if (a0 != a1) {
    double u = a0 / (a0 - a1);  // root of the linear p''
    if (u > 0 && u < 1) best = std::max(best, std::abs(d1(u)));
  }
  return {best / h, std::max(std::abs(a0), std::abs(a1)) / (h * h)};
}

Analyzer::Analyzer(const Table& table, CancelMode mode, double start_ref, const AxisVec& start_pos,
                   std::uint32_t repetitions)
    : table_(&table),
      mode_(mode),
      start_ref_(start_ref),
      start_pos_(start_pos),
      modal_(start_pos),
      repetitions_(std::max<std::uint32_t>(1, repetitions)) {}

double Analyzer::analyse_row(const Row& row, const Values& values, double t_s) {
  const std::string& file = table_->file;
  if (row.cancel) {  // SA02 → SA09, SA10
    shifting_ = false;
    if (mode_ == CancelMode::kClear) offset_ -= amount_;  // back to the written values
    // kRebase: the running reference is reset by the amount, so offset_ stays as it is.
    amount_ = 0;
  } else if (row.shift.kind != Shift::Kind::kNone) {  // SA05–SA07
    double a = 0;
    switch (row.shift.kind) {
      case Shift::Kind::kDirect:
        a = row.shift.amount;
        break;
      case Shift::Kind::kParam: {
        auto it = values.params.find(row.shift.number);
        if (it == values.params.end()) {
          throw InputError(file, row.line, row.shift.col,
                           fmt::format("parameter P{} is not defined", row.shift.number));
        }
        a = it->second;
        break;
      }
      case Shift::Kind::kMacro: {
        auto it = values.macros.find(row.shift.number);
        if (it == values.macros.end()) {
          throw InputError(file, row.line, row.shift.col,
                           fmt::format("macro variable #{} is not defined", row.shift.number));
        }
        a = it->second;
        break;
      }
      case Shift::Kind::kSignal: {
        bool found = false;
        a = value_of_signal(values, row.shift.number, t_s, found);
        if (!found) {
          throw InputError(file, row.line, row.shift.col,
                           fmt::format("signal R{} is not defined", row.shift.number));
        }
        break;
      }
      case Shift::Kind::kNone:
        break;
    }
    shifting_ = true;
    amount_ += a;
    offset_ += a;
  }
  // SA04/SA08/SA11: shifted reference (offset_ is 0 while shifting was never on).
  return row.ref_written + offset_ + rep_offset_;
}

bool Analyzer::next(const Values& values, double t_s, EffectivePoint& out) {
  if (pending_) {
    out = pending_point_;
    pending_ = false;
    return true;
  }
  const auto& rows = table_->rows;
  if (row_ >= rows.size()) {
    if (!table_->cyclic || rep_ + 1 >= repetitions_) return false;
    // Next repetition: fresh shift state; its first row is the point just ended.
    ++rep_;
    shifting_ = false;
    amount_ = offset_ = 0;
    rep_offset_ = 0;
    double r0 = analyse_row(rows[0], values, t_s);
    rep_offset_ = prev_ref_ - r0;
    row_ = 1;
  }
  const Row& row = rows[row_];
  double ref = analyse_row(row, values, t_s);
  for (std::size_t i = 0; i < kMaxAxes; ++i) {
    if ((row.axis_mask >> i) & 1U) modal_[i] = row.target[i];
  }
  EffectivePoint p;
  p.ref = ref;
  p.position = modal_;
  p.row = static_cast<std::int32_t>(row_);
  p.shift = offset_;
  p.shifting = shifting_;
  bool last_row = row_ + 1 == rows.size();
  if (table_->cyclic && last_row && rep_ + 1 < repetitions_) p.extra_row = 0;

  auto describe = [&]() {
    std::string s = fmt::format("reference L{}", row.ref_written);
    if (ref != row.ref_written) s += fmt::format(" (effective {} after shifts)", ref);
    return s;
  };
  if (!have_prev_) {
    if (ref < start_ref_) {
      throw InputError(
          table_->file, row.line, row.col,
          fmt::format("{} is before the start of the reference ({})", describe(), start_ref_));
    }
    have_prev_ = true;
    prev_ref_ = ref;
    prev_line_ = row.line;
    ++row_;
    if (ref > start_ref_) {  // implicit start point first, then this row
      pending_ = true;
      pending_point_ = p;
      EffectivePoint s;
      s.ref = start_ref_;
      s.position = start_pos_;
      out = s;
      return true;
    }
    out = p;
    return true;
  }
  if (!(ref > prev_ref_)) {
    throw InputError(
        table_->file, row.line, row.col,
        fmt::format("{} does not increase over the previous control point ({}, line {})",
                    describe(), prev_ref_, prev_line_));
  }
  prev_ref_ = ref;
  prev_line_ = row.line;
  ++row_;
  out = p;
  return true;
}

}  // namespace cncore::tables::detail
