// A recorded trajectory: one entry per interpolation cycle, from a trajectory CSV (spec 05) or
// appended from in-memory samples. Knows nothing about the motion kernel's types.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "core/geometry.hpp"

namespace cncore::testing {

struct Trajectory {
  double period_s = 0.001;  // τ; the loader takes it from the t column
  // Rounding of the positions: 0 for exact in-memory samples; the loader sets half a unit of the
  // last decimal printed (5e-7 mm for 6 decimals). The checker adds it to its slacks.
  double position_resolution_mm = 0;
  std::vector<double> t_s;
  std::vector<std::uint32_t> line;
  std::vector<AxisVec> pos;  // axis set-points (mm, degrees for A B C)
  std::vector<double> feed_mm_min;
  std::vector<double> override_pct;  // 100 when the source had none
  std::vector<double> correction;    // spec 03 coefficient; 1 when the source had none

  std::size_t size() const { return pos.size(); }
  bool empty() const { return pos.empty(); }
  void reserve(std::size_t n);
  void add(double t, std::uint32_t line_no, const AxisVec& p, double feed = 0,
           double override = 100, double corr = 1);
  // Any sample-like struct with t_s, line, position, feed_mm_min, override_pct (e.g.
  // cncore::motion::Sample), without including its header here.
  template <class S>
  void add_sample(const S& s) {
    add(s.t_s, s.line, s.position, s.feed_mm_min, s.override_pct);
  }
};

// Reads a trajectory CSV: a header row naming the columns (any order, extra columns ignored;
// required t, line, and at least one of x y z a b c; optional feed, override, correction), then
// one row per cycle. Streams the file once; a few million rows load in about a second.
// Throws std::runtime_error("FILE:LINE: ...") on a missing column or a bad number.
Trajectory load_trajectory_csv(const std::string& path);

}  // namespace cncore::testing
